"""Which agents can ever exist in an episode: PettingZoo's fixed ``possible_agents``.

An agent is an RL vehicle and its id is the vehicle id, as in Flow (whose RLlib agents were
keyed by vehicle id). SUMO names the vehicles of a ``<flow>`` ``{flow id}.{k}`` with ``k``
counting from 0 in departure order, and never reuses an id within a run, so the ids an episode
can produce are known before it starts:

* the RL vehicles placed at reset: ``{group}_{i}`` for each RL group (``RLController``);
* for each inflow of an RL group, ``{flow id}.0 .. {flow id}.{n-1}`` with ``n`` an upper bound
  of the departures it schedules before the episode ends: one per ``period`` (``3600 /
  vehs_per_hour``) from ``begin``, at most one per simulation step for ``probability``
  inflows, never more than ``number``.

An id beyond the bound (it cannot happen with SUMO's schedule) is not an agent: the car is
left to drive without commands and a warning is logged.
"""

from __future__ import annotations

import math

from flowrun.config.inflows import InFlow, InFlows
from flowrun.config.vehicles import VehicleParams, is_rl


def rl_groups(vehicles: VehicleParams) -> set[str]:
    """Names of the vehicle groups driven by the RL agent."""
    return {g.veh_id for g in vehicles.groups if is_rl(g)}


def max_departures(flow: InFlow, until: float, dt: float) -> int:
    """Upper bound of the vehicles ``flow`` departs at or before ``until`` seconds.

    Args:
        flow: the inflow.
        until: end of the episode, simulation seconds.
        dt: simulation step, s (the finest schedule of a ``probability`` inflow).
    """
    last = until if flow.number is not None else min(until, float(flow.end))
    if last < flow.begin:
        return 0
    if flow.probability is not None:
        interval = dt
    elif flow.period is not None:
        interval = float(flow.period)
    else:
        assert flow.vehs_per_hour is not None  # InFlow checks that one rate is given
        interval = 3600.0 / float(flow.vehs_per_hour)
    # +1 for the departure at ``begin``, +1 for SUMO rounding departures to whole steps
    count = math.floor((last - flow.begin) / interval + 1e-9) + 2
    return count if flow.number is None else min(count, int(flow.number))


def possible_agent_ids(
    vehicles: VehicleParams, inflows: InFlows | None, episode_seconds: float, dt: float
) -> list[str]:
    """Every RL vehicle id an episode can produce, placed vehicles first (see the module).

    Args:
        vehicles: the experiment's vehicle groups.
        inflows: the network's inflows (``None``: none).
        episode_seconds: simulated time of a whole episode (warm-up included), s.
        dt: simulation step, s.
    """
    groups = rl_groups(vehicles)
    ids = [f"{g.veh_id}_{i}" for g in vehicles.groups if is_rl(g) for i in range(g.num_vehicles)]
    if inflows is None:
        return ids
    for flow, flow_id in zip(inflows.flows, inflows.sumo_ids(), strict=True):
        if flow.veh_type in groups:
            n = max_departures(flow, episode_seconds, dt)
            ids.extend(f"{flow_id}.{k}" for k in range(n))
    return ids
