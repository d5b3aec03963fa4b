"""The RL bottleneck envs (Flow's ``flow.envs.bottleneck``): AVs that accelerate and change
lanes (``BottleneckAccelEnv``), and AVs told how fast to drive in each stretch
(``BottleneckDesiredVelocityEnv``, Flow's bottleneck0-2 benchmarks; alias
``DesiredVelocityEnv``). Flow's module also holds the base env: :class:`BottleneckEnv` and
its ``ADDITIONAL_ENV_PARAMS`` are re-exported from :mod:`flowrun.envs.bottleneck_base`, and
``BottleneckAccelEnv`` from :mod:`flowrun.envs.bottleneck_accel`.

Vinitsky et al., "Lagrangian Control through Deep-RL: Applications to Bottleneck
Decongestion", ITSC 2018. For the desired-velocity env the road is cut into cells: each edge
into equal segments, each segment into its lanes. The agent sees how many humans and AVs are
in each observed cell and how fast they go, and moves each controlled cell's speed cap up or
down; every AV in that cell takes the new cap as its maximum speed (SUMO drives it within
the cap).
"""

from __future__ import annotations

import dataclasses
from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.config.inflows import InFlows
from flowrun.config.params import NetParams
from flowrun.envs.bottleneck_accel import ADDITIONAL_RL_ENV_PARAMS, BottleneckAccelEnv
from flowrun.envs.bottleneck_base import (
    ADDITIONAL_ENV_PARAMS,
    MAX_LANES,
    NUM_VEHICLE_NORM,
    BottleneckEnv,
)
from flowrun.errors import ConfigError
from flowrun.networks.base import Network

__all__ = [
    "ADDITIONAL_ENV_PARAMS",
    "ADDITIONAL_RL_ENV_PARAMS",
    "ADDITIONAL_VSL_ENV_PARAMS",
    "MAX_LANES",
    "BottleNeckAccelEnv",
    "BottleneckAccelEnv",
    "BottleneckDesiredVelocityEnv",
    "BottleneckEnv",
    "DesiredVelocityEnv",
]

#: Flow's speed normalisation of the observation (m/s) and of the outflow (veh/h).
SPEED_NORM, OUTFLOW_NORM = 50.0, 2000.0
#: Flow's bounds of an AV's speed cap, m/s (the upper one is Flow's bottleneck speed limit).
MIN_CAP, MAX_CAP = 0.01, 23.0

ADDITIONAL_VSL_ENV_PARAMS: dict[str, Any] = {
    # (edge, number of segments, controlled) per edge
    "controlled_segments": [
        ("1", 1, True),
        ("2", 1, True),
        ("3", 1, True),
        ("4", 1, True),
        ("5", 1, True),
    ],
    # one action per segment for all its lanes (true) or one per lane (false)
    "symmetric": False,
    # (edge, number of segments) per observed edge
    "observed_segments": [("1", 1), ("2", 1), ("3", 1), ("4", 1), ("5", 1)],
    # draw a new total inflow at each reset
    "reset_inflow": False,
    # the range the total inflow is drawn from, veh/h (times the scaling)
    "inflow_range": [1000, 2000],
}


def _segments(value: Any, key: str, width: int) -> list[tuple[Any, ...]]:
    """Flow's segment lists as tuples of ``width`` (YAML gives lists)."""
    if not isinstance(value, list | tuple) or not all(
        isinstance(s, list | tuple) and len(s) == width for s in value
    ):
        raise ConfigError(
            f"expected a list of {width}-element entries, got {value!r}",
            path=f"env.additional_params.{key}",
        )
    return [tuple(s) for s in value]


class BottleneckDesiredVelocityEnv(BottleneckEnv):
    """Variable speed caps for the AVs in the bottleneck (Flow's
    ``BottleneckDesiredVelocityEnv``).

    Observation: for each observed cell (edge, segment, lane; edges in ``observed_segments``
    order, segments along the edge, lanes from the right), in four blocks: humans / 20, AVs
    / 20, humans' mean speed / 50, AVs' mean speed / 50 (0 for an empty cell); then the
    outflow over the last ``20 * sim_step`` s / 2000. Values are clipped to [0, 1] (Flow
    declared [0, 1] but a crowded cell's count can exceed it).
    Action: per controlled cell (``symmetric``: per controlled segment) a change of the
    speed cap, m/s, within ``[-max_decel * sim_step, max_accel * sim_step]``. Each AV on a
    controlled cell gets ``clip(cap + change, 0.01, 23)`` as its maximum speed; elsewhere
    its cap returns to 23 m/s.
    Reward: outflow over the last ``10 * sim_step`` s / ``(2000 * scaling)``; in evaluate
    mode, the outflow over the last 500 s at the horizon (veh/h), 0 before.
    ``reset_inflow``: each reset scales the network's inflows (keeping their shares) to a
    total drawn uniformly from ``inflow_range`` times the scaling.
    Termination: collision; truncation: horizon.
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = {
        **ADDITIONAL_ENV_PARAMS,
        **ADDITIONAL_VSL_ENV_PARAMS,
    }

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        p = self.env_params.additional_params
        self.segments = _segments(p["controlled_segments"], "controlled_segments", 3)
        self.obs_segments = _segments(p["observed_segments"], "observed_segments", 2)
        self.symmetric = bool(p["symmetric"])
        net = self.k.network
        for edge, *_ in self.segments + self.obs_segments:
            if net.num_lanes(str(edge)) < 1:
                raise ConfigError(
                    f"edge {edge!r} is not an edge of the network "
                    f"({', '.join(net.get_edge_list())})",
                    path="env.additional_params.controlled_segments",
                )
        #: edge -> segment boundaries along it, m (controlled / observed)
        self.slices = {str(e): np.linspace(0, net.edge_length(str(e)), int(n) + 1)
                       for e, n, _ in self.segments}  # fmt: skip
        self.obs_slices = {str(e): np.linspace(0, net.edge_length(str(e)), int(n) + 1)
                           for e, n in self.obs_segments}  # fmt: skip
        #: edge -> index of its first action (controlled edges only)
        self.action_index: dict[str, int] = {}
        size = 0
        for edge, n, controlled in self.segments:
            if controlled:
                self.action_index[str(edge)] = size
                size += int(n) * (1 if self.symmetric else net.num_lanes(str(edge)))
        self._num_actions = size
        self._num_cells = sum(int(n) * net.num_lanes(str(e)) for e, n in self.obs_segments)
        self._base_inflows = self.net_params.inflows

    @property
    def action_space(self) -> Box:  # type: ignore[override]
        """One speed-cap change (m/s) per controlled cell or segment."""
        p = self.env_params.additional_params
        return Box(
            low=-abs(float(p["max_decel"])) * self.sim_step,
            high=float(p["max_accel"]) * self.sim_step,
            shape=(self._num_actions,),
            dtype=np.float32,
        )

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """Four values per observed cell and the outflow."""
        return Box(low=0.0, high=1.0, shape=(4 * self._num_cells + 1,), dtype=np.float32)

    def get_state(self) -> Any:
        """Counts and mean speeds of humans and AVs per observed cell, and the outflow."""
        vk = self.k.vehicle
        edges, lanes, pos = vk.edges, vk.lanes, vk.lane_pos
        speed, is_rl = vk.speed, vk.table.is_rl
        blocks: list[list[np.ndarray]] = [[], [], [], []]
        for edge, n in self.obs_segments:
            e = str(edge)
            num_lanes = self.k.network.num_lanes(e)
            rows = np.flatnonzero(np.fromiter((x == e for x in edges), bool, len(edges)))
            seg = np.clip(np.searchsorted(self.obs_slices[e], pos[rows], side="right") - 1,
                          0, int(n) - 1)  # fmt: skip
            cell = seg * num_lanes + np.minimum(lanes[rows], num_lanes - 1)
            size = int(n) * num_lanes
            for k, rl in enumerate((False, True)):
                mine = is_rl[rows] == rl
                count = np.bincount(cell[mine], minlength=size).astype(np.float64)
                total = np.bincount(cell[mine], weights=speed[rows][mine], minlength=size)
                mean = np.divide(total, count, out=np.zeros(size), where=count > 0)
                blocks[k].append(count / NUM_VEHICLE_NORM)
                blocks[2 + k].append(mean / SPEED_NORM)
        outflow = vk.get_outflow_rate(20 * self.sim_step) / OUTFLOW_NORM
        obs = np.concatenate([np.concatenate(b) for b in blocks] + [np.array([outflow])])
        return np.clip(obs, 0.0, 1.0)

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        actions = np.asarray(rl_actions, dtype=np.float64).reshape(-1)
        vk = self.k.vehicle
        speed_limit = float(self.net_params.additional_params.get("speed_limit", MAX_CAP))
        for rl_id in vk.get_rl_ids():
            edge = vk.get_edge(rl_id)
            if edge not in self.action_index:  # not controlled, or a junction's link
                vk.set_max_speed(rl_id, speed_limit)
                continue
            slices = self.slices[edge]
            seg = int(np.searchsorted(slices, vk.get_position(rl_id), side="right")) - 1
            seg = min(max(seg, 0), len(slices) - 2)
            if self.symmetric:
                i = self.action_index[edge] + seg
            else:
                num_lanes = self.k.network.num_lanes(edge)
                i = self.action_index[edge] + seg * num_lanes + vk.get_lane(rl_id)
            cap = float(np.clip(vk.get_max_speed(rl_id) + actions[i], MIN_CAP, MAX_CAP))
            vk.set_max_speed(rl_id, cap)

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Outflow reward (see the class docstring)."""
        if self.env_params.evaluate:
            if self.step_counter == self.env_params.horizon:
                return self.k.vehicle.get_outflow_rate(500)
            return 0.0
        return super().compute_reward(rl_actions, **kwargs)

    def episode_network(self) -> Network:
        """The network with a newly drawn total inflow when ``reset_inflow`` (seeded)."""
        p = self.env_params.additional_params
        if not p["reset_inflow"] or self._base_inflows is None:
            return self.network
        low, high = (float(v) for v in p["inflow_range"])
        total = float(self.np_random.uniform(min(low, high), max(low, high))) * self.scaling
        flows = list(self._base_inflows.get())
        base = sum(float(f.vehs_per_hour or 0.0) for f in flows)
        if base <= 0:
            raise ConfigError("reset_inflow scales the inflows' vehs_per_hour; none has one",
                              path="env.additional_params.reset_inflow")  # fmt: skip
        scaled = [dataclasses.replace(f, vehs_per_hour=float(f.vehs_per_hour or 0.0) * total / base)
                  for f in flows]  # fmt: skip
        net = self.network
        return type(net)(
            net.orig_name,
            net.vehicles,
            NetParams(
                additional_params=dict(net.net_params.additional_params), inflows=InFlows(scaled)
            ),
            net.initial_config,
            net.traffic_lights,
        )


#: Flow's deprecated alias of :class:`BottleneckDesiredVelocityEnv`.
DesiredVelocityEnv = BottleneckDesiredVelocityEnv
#: Flow's deprecated spelling of :class:`BottleneckAccelEnv` (``flow.envs.bottleneck_env``)
BottleNeckAccelEnv = BottleneckAccelEnv
