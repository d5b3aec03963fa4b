"""The RL bottleneck envs (Flow's ``flow.envs.bottleneck``): AVs that accelerate and change
lanes (``BottleneckAccelEnv``), and AVs told how fast to drive in each stretch
(``BottleneckDesiredVelocityEnv``, Flow's bottleneck0-2 benchmarks; alias
``DesiredVelocityEnv``). Flow's module also holds the base env: :class:`BottleneckEnv` and
its ``ADDITIONAL_ENV_PARAMS`` are re-exported from :mod:`flowrun.envs.bottleneck_base`.

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
from flowrun.envs.bottleneck_base import (
    ADDITIONAL_ENV_PARAMS,
    MAX_LANES,
    NUM_VEHICLE_NORM,
    BottleneckEnv,
)
from flowrun.envs.rewards import desired_velocity
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

ADDITIONAL_RL_ENV_PARAMS: dict[str, Any] = {
    # desired speed of all cars, m/s (the reward's target)
    "target_velocity": 30,
    # put an AV that left the network back at the start of edge 1
    "add_rl_if_exit": True,
}

#: Flow's normalisation of positions and gaps, m, and of edge numbers
POSITION_NORM, EDGE_NORM = 1000.0, 6.0
#: Flow's reward weights: forward progress of the AVs, lane-change actions
PROGRESS_GAIN, LANE_CHANGE_GAIN = 0.1, 1.0
#: Flow's bottleneck has one more edge, ``fake_edge`` (1 m, off the road, drawn for the GUI
#: only); it is in Flow's ``get_edge_list()`` (last: SUMO lists edges by id), so Flow's
#: observation ends with its pair (mean speed, density), always (0, 0): kept, as Flow's
FLOW_FAKE_EDGE_PAIR = np.zeros(2)


class BottleneckAccelEnv(BottleneckEnv):
    """Accelerations and lane changes for a fixed set of AVs (Flow's ``BottleneckAccelEnv``).

    The AVs are those placed at the start (``rl_id_list``); with ``add_rl_if_exit`` an AV
    that leaves re-enters at the start of edge ``1`` (lane ``i mod lanes`` for the i-th AV,
    at its maximum speed), so the observation and action keep their meaning.

    Observation (in [0, 1]; values outside are clipped, e.g. Flow's -1 edge code on a
    junction's link becomes 0), ``4 + 16 * scaling`` values per AV then 2 per edge:
    per AV in ``rl_id_list`` order (zeros while it is away): ``x / 1000``, ``v / v_max``,
    ``lane / 4``, ``edge / 6``; per AV, over ``4 * scaling`` lanes: gaps to the nearest car
    ahead / behind on each lane of its edge (``/ 1000``; 1 without one), their speeds
    ``/ v_max`` (0 without one); per edge: mean speed ``/ v_max`` and cars per metre, then
    Flow's pair (0, 0) of its off-road ``fake_edge`` (:data:`FLOW_FAKE_EDGE_PAIR`).
    Action: per AV ``[acceleration, lane-change direction]`` (direction rounded: -1 right,
    +1 left), for the AVs present ordered by position; a car changes lane at most once per
    ``lane_change_duration`` simulation steps.
    Reward: desired velocity towards ``target_velocity`` + 0.1 * sum of the AVs' speeds -
    the number of lane changes asked (Flow's). Termination: collision; truncation: horizon.
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = {
        **ADDITIONAL_ENV_PARAMS,
        **ADDITIONAL_RL_ENV_PARAMS,
    }

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        vehicles = self.initial_vehicles
        #: the AVs' ids, fixed for the env's life (Flow's ``rl_id_list``)
        self.rl_id_list = [
            f"{g.veh_id}_{i}"
            for g, control in zip(vehicles.groups, self.controls, strict=True)
            if control.controller.is_rl
            for i in range(g.num_vehicles)
        ]
        self.num_rl = len(self.rl_id_list)
        self._rl_type = {v: v.rsplit("_", 1)[0] for v in self.rl_id_list}
        self.add_rl_if_exit = bool(self.env_params.additional_params["add_rl_if_exit"])
        self._lanes = MAX_LANES * self.scaling

    @property
    def action_space(self) -> Box:  # type: ignore[override]
        """Acceleration and lane-change direction per AV, interleaved."""
        p = self.env_params.additional_params
        low = np.tile([-abs(float(p["max_decel"])), -1.0], self.num_rl)
        high = np.tile([float(p["max_accel"]), 1.0], self.num_rl)
        return Box(low=low.astype(np.float32), high=high.astype(np.float32), dtype=np.float32)

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """Per-AV state, per-AV neighbours on every lane, per-edge speed and density."""
        n = 4 * self.num_rl + 4 * self._lanes * self.num_rl + 2 * len(self._edges())
        n += FLOW_FAKE_EDGE_PAIR.size
        return Box(low=0.0, high=1.0, shape=(n,), dtype=np.float32)

    def _edges(self) -> list[str]:
        return self.k.network.get_edge_list()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start a new episode; lane changes are logged from here on (``get_last_lc``)."""
        obs, info = super().reset(seed=seed, options=options)
        self.k.vehicle.lane_change_log()
        return obs, info

    def get_state(self) -> Any:
        """See the class docstring."""
        vk, net = self.k.vehicle, self.k.network
        v_max, lanes = net.max_speed(), self._lanes
        own = np.zeros((self.num_rl, 4))
        near = np.zeros((self.num_rl, 4, lanes))
        near[:, :2] = 1.0  # no car ahead / behind: the largest gap
        for i, rl in enumerate(self.rl_id_list):
            if rl not in vk.table:
                continue
            edge = vk.get_edge(rl)
            code = int(edge) / EDGE_NORM if edge.isdigit() else -1.0
            own[i] = (vk.get_x_by_id(rl) / POSITION_NORM, vk.get_speed(rl) / v_max,
                      vk.get_lane(rl) / MAX_LANES, code)  # fmt: skip
            ahead, behind = vk.get_lane_headways(rl), vk.get_lane_tailways(rl)
            m = min(len(ahead), lanes)
            near[i, 0, :m] = np.asarray(ahead[:m]) / POSITION_NORM
            near[i, 1, :m] = np.asarray(behind[:m]) / POSITION_NORM
            near[i, 2, :m] = np.asarray(vk.get_lane_leaders_speed(rl)[:m]) / v_max
            near[i, 3, :m] = np.asarray(vk.get_lane_followers_speed(rl)[:m]) / v_max
        per_edge = []
        for edge in self._edges():
            ids = vk.get_ids_by_edge(edge)
            if ids:
                speed = float(np.mean(vk.get_speed(ids))) / v_max
                per_edge += [speed, len(ids) / net.edge_length(edge)]
            else:
                per_edge += [0.0, 0.0]
        obs = np.concatenate(
            [own.reshape(-1), near.reshape(-1), np.array(per_edge), FLOW_FAKE_EDGE_PAIR]
        )
        return np.clip(np.nan_to_num(obs, posinf=1.0), 0.0, 1.0)

    def _present_rl(self) -> list[str]:
        vk = self.k.vehicle
        return sorted((v for v in self.rl_id_list if v in vk.table), key=vk.get_x_by_id)

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        vk = self.k.vehicle
        rl_ids = self._present_rl()
        actions = np.asarray(rl_actions, dtype=np.float64).reshape(-1)
        n = len(rl_ids)
        if not n:
            return
        accel, direction = actions[::2][:n], np.rint(actions[1::2])[:n]
        wait = float(self.env_params.additional_params["lane_change_duration"])
        blocked = [self.time_counter <= wait + vk.get_last_lc(v) for v in rl_ids]
        vk.apply_acceleration(rl_ids, accel)
        vk.apply_lane_change(rl_ids, np.where(blocked, 0.0, direction))

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Flow's: desired velocity + AV forward progress - lane changes asked."""
        vk = self.k.vehicle
        if kwargs.get("fail", False):
            self.reward_terms = {}
            return 0.0
        target = float(self.env_params.additional_params["target_velocity"])
        n = len(self._present_rl())
        asked = 0.0
        if rl_actions is not None and n:
            asked = float(np.abs(np.rint(np.asarray(rl_actions).reshape(-1)[1::2][:n])).sum())
        rl_speed = vk.speed[vk.table.is_rl] if vk.table.size else np.zeros(0)
        self.reward_terms = {
            "desired_velocity": desired_velocity(vk.speed, target),
            "forward_progress": PROGRESS_GAIN * float(np.abs(rl_speed).sum()),
            "lane_change_penalty": -LANE_CHANGE_GAIN * asked,
        }
        return sum(self.reward_terms.values())

    def additional_command(self) -> None:
        """Count the bottleneck's cars; put AVs that left back at the start (Flow's)."""
        super().additional_command()
        if not self.add_rl_if_exit:
            return
        vk = self.k.vehicle
        for i, rl in enumerate(self.rl_id_list):
            if rl not in vk.table:
                vk.add(rl, self._rl_type[rl], "1", 0.0, i % self._lanes, "max")


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
