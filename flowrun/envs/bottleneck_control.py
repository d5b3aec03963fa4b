"""Flow's toll booth and ALINEA ramp meter on the bottleneck (``disable_tb`` /
``disable_ramp_metering`` false), as traffic lights on nodes ``2`` and ``3``.

Both hold the cars that approach them in their lane (SUMO lane-change mode 512, no lane
changes) and give them back their own mode once they are past.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: Flow's largest number of lanes per unit of ``scaling``
MAX_LANES = 4

#: Flow's toll booth: mean waits (s) at a normal and a fast-track booth, the distance into
#: edge ``1`` (m) after which cars stop changing lanes, and after which the booth holds them
MEAN_WAIT_TOLL, MEAN_WAIT_FAST_TRACK = 15.0, 3.0
TOLL_BOOTH_AREA, TOLL_STOP_AREA = 10.0, 50.0
#: Flow's ramp meter: the distance into edge ``2`` (m) after which cars stop changing lanes
RAMP_METER_AREA = 80.0
#: SUMO lane-change mode of a car held in its lane (Flow's ``no_lc_safe``)
HOLD_LANE = 512


class _LaneHold:
    """Cars held in their lane: id -> their own lane-change mode, given back later."""

    def __init__(self) -> None:
        self.held: dict[str, int] = {}

    def hold(self, vk: Any, veh_id: str) -> None:
        self.held[veh_id] = vk.get_lane_change_mode(veh_id)
        vk.set_lane_change_mode(veh_id, HOLD_LANE)

    def release_on(self, vk: Any, edge: str) -> list[str]:
        """Give their mode back to the held cars now on ``edge`` (forget those gone)."""
        out = []
        for veh_id in list(self.held):
            if veh_id not in vk.table:
                del self.held[veh_id]
            elif vk.get_edge(veh_id) == edge:
                vk.set_lane_change_mode(veh_id, self.held.pop(veh_id))
                out.append(veh_id)
        return out


def _on_edge(vk: Any, edge: str, beyond: float) -> list[tuple[str, int, float]]:
    """``(id, lane, position)`` of the cars on ``edge`` more than ``beyond`` m into it."""
    ids, edges, lanes, pos = vk.table.ids, vk.edges, vk.lanes, vk.lane_pos
    return [(ids[i], int(lanes[i]), float(pos[i]))
            for i, e in enumerate(edges) if e == edge and pos[i] > beyond]  # fmt: skip


class TollBooth:
    """Flow's toll booth on node ``2``: each lane's light stays red for a random wait.

    A lane's wait (in steps) is drawn from a normal law, mean 15 s (3 s at the fast-track
    booths, the middle lanes), sd 1 s, and counts down while a car stands in the last
    50 m of edge ``1``; the next wait is drawn when a car passes.
    """

    def __init__(self, scaling: int, dt: float, rng: np.random.Generator) -> None:
        self.dt, self.rng = dt, rng
        n = MAX_LANES * scaling
        self.fast_track = range(math.ceil(1.5 * scaling), math.ceil(2.6 * scaling))
        self.wait = np.abs(rng.normal(MEAN_WAIT_TOLL / dt, 4 / dt, n))
        self.state = ""
        self.lanes = _LaneHold()

    def step(self, k: Any) -> None:
        """Release the cars past the booth, hold the ones in it, set the lights."""
        vk = k.vehicle
        for veh_id in self.lanes.release_on(vk, "2"):
            lane = vk.get_lane(veh_id)
            mean = MEAN_WAIT_FAST_TRACK if lane in self.fast_track else MEAN_WAIT_TOLL
            self.wait[lane] = max(0.0, float(self.rng.normal(mean / self.dt, 1 / self.dt)))
        lights = ["G"] * self.wait.size
        for veh_id, lane, pos in _on_edge(vk, "1", TOLL_BOOTH_AREA):
            if veh_id not in self.lanes.held:
                self.lanes.hold(vk, veh_id)
            elif pos > TOLL_STOP_AREA and lane < self.wait.size and self.wait[lane] >= 0:
                lights[lane] = "r"  # Flow counts the wait down per waiting car
                self.wait[lane] -= 1
        state = "".join(lights)
        if state != self.state:
            self.state = state
            k.traffic_light.set_state("2", state)


class RampMeter:
    """Flow's ALINEA ramp meter on node ``3`` (Spiliopoulou, Papamichail, Papageorgiou,
    "Toll plaza merging traffic control for throughput maximization", J. Transp. Eng. 2009).

    Every ``feedback_update`` s the metered flow ``q`` (veh/h) moves by
    ``feedback_coeff * (n_crit - n)``, ``n`` the mean number of cars on edge ``4`` over the
    last 10 steps, within ``[q_min, q_max]``; each lane's light is green for the first
    ``green_time`` = 4 s of every ``7200 / q`` s cycle, the lanes' cycles offset by 8 s.
    """

    def __init__(self, scaling: int, dt: float, params: dict[str, Any]) -> None:
        self.dt = dt
        self.n_crit = float(params.get("n_crit", 8))
        self.q_max = float(params.get("q_max", 1100))
        self.q_min = float(params.get("q_min", 0.25 * 1100))
        self.feedback_update = float(params.get("feedback_update", 15))
        self.feedback_coeff = float(params.get("feedback_coeff", 20))
        self.q = self.q_min
        self.cycle_time, self.green_time, self.timer = 6.0, 4.0, 0.0
        n = MAX_LANES * scaling
        self.ramp_state = np.linspace(0, 8 * n, n)
        self.lanes = _LaneHold()

    def step(self, k: Any, cars_in_bottleneck: list[int]) -> None:
        """Hold the cars approaching the meter, update ALINEA, set the lights."""
        vk = k.vehicle
        self.lanes.release_on(vk, "3")
        for veh_id, _, _ in _on_edge(vk, "2", RAMP_METER_AREA):
            if veh_id not in self.lanes.held:
                self.lanes.hold(vk, veh_id)
        self.timer += self.dt
        self.ramp_state += self.dt
        if self.timer > self.feedback_update:
            self.timer = 0.0
            update = self.feedback_coeff * (self.n_crit - float(np.mean(cars_in_bottleneck)))
            self.q = float(np.clip(self.q + update, self.q_min, self.q_max))
            self.cycle_time = 7200.0 / self.q
        self.ramp_state %= self.cycle_time
        state = "".join("G" if s <= self.green_time else "r" for s in self.ramp_state)
        k.traffic_light.set_state("3", state)
