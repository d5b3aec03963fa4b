"""Flow's ``BottleneckAccelEnv``: a fixed set of AVs that accelerate and change lanes in the
bottleneck (importable from :mod:`flowrun.envs.bottleneck`, Flow's module path)."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.bottleneck_base import (
    ADDITIONAL_ENV_PARAMS,
    MAX_LANES,
    BottleneckEnv,
)
from flowrun.envs.lane_change_log import LogsLaneChanges
from flowrun.envs.lane_observation import lane_neighbours
from flowrun.envs.rewards import desired_velocity

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


class BottleneckAccelEnv(LogsLaneChanges, BottleneckEnv):
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

    def get_state(self) -> Any:
        """See the class docstring."""
        vk, net = self.k.vehicle, self.k.network
        v_max, lanes = net.max_speed(), self._lanes
        own = np.zeros((self.num_rl, 4))
        near = np.zeros((self.num_rl, 4, lanes))
        near[:, :2] = 1.0  # AVs away: no car ahead / behind
        for i, rl in enumerate(self.rl_id_list):
            if rl not in vk.table:
                continue
            edge = vk.get_edge(rl)
            code = int(edge) / EDGE_NORM if edge.isdigit() else -1.0
            own[i] = (vk.get_x_by_id(rl) / POSITION_NORM, vk.get_speed(rl) / v_max,
                      vk.get_lane(rl) / MAX_LANES, code)  # fmt: skip
            near[i] = lane_neighbours(vk, rl, lanes, POSITION_NORM, v_max)
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
