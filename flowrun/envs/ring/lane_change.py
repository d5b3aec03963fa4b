"""``LaneChangeAccelEnv``: RL cars choose accelerations and lane changes on a multi-lane
ring or highway (Flow's ``flow.envs.ring.lane_change_accel``)."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.lane_change_log import LogsLaneChanges
from flowrun.envs.lane_observation import lane_neighbours
from flowrun.envs.ring.accel import AccelEnv, clip_unit, fit

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the RL cars, m/s^2
    "max_accel": 3,
    # maximum deceleration of the RL cars, m/s^2
    "max_decel": 3,
    # simulation steps an RL car waits after a lane change before it may change again
    # (Flow's counter counts steps although its comment says seconds)
    "lane_change_duration": 5,
    # desired speed of all cars, m/s
    "target_velocity": 10,
    # observe cars sorted by position instead of by id
    "sort_vehicles": False,
}


LANE_CHANGE_PENALTY = 0.1  # reward lost per RL lane change (Flow: 10% of the best reward)


class LaneChangeAccelEnv(LogsLaneChanges, AccelEnv):
    """Acceleration and lane-change actions for the RL cars (Flow's ``LaneChangeAccelEnv``),
    on a multi-lane ring or an open multi-lane road (the highway).

    Observation: ``3 * num_vehicles`` values in [0, 1] (``num_vehicles`` = the cars placed
    at the start; zero-padded or cut when cars come and go): speeds / max speed, positions
    ``get_x_by_id`` / length, lanes / the largest number of lanes (Flow's normalisation), in
    :attr:`sorted_ids` order.
    Action: per RL car an acceleration in ``[-max_decel, max_accel]`` and a lane-change
    direction in ``[-1, 1]`` (rounded: -1 right, 0 stay, +1 left), interleaved
    ``[a_0, d_0, a_1, d_1, ...]``, for the RL cars present in :attr:`sorted_ids` order
    (extra actions are ignored). As Flow, a car whose last lane change (``get_last_lc``)
    is at most ``lane_change_duration`` simulation steps ago keeps its lane.
    Reward: desired velocity, as :class:`AccelEnv`, minus 0.1 for every RL car that
    changed lane in the last simulation step (``info["reward_terms"]``:
    ``desired_velocity``, ``lane_change_penalty``); the mean speed in evaluate mode.
    ``info["lane_changes"]``: lane changes of all cars since the episode's first observation.
    Termination: collision; truncation: horizon.
    """

    DEFAULT_EXPERIMENT = "envs/ring_lane_change.yaml"  # a two-lane ring

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS

    @property
    def action_space(self) -> Box:  # type: ignore[override]
        """Acceleration and lane-change direction per RL vehicle, interleaved."""
        p = self.env_params.additional_params
        n = self.initial_vehicles.num_rl_vehicles
        low = np.tile([-abs(float(p["max_decel"])), -1.0], n).astype(np.float32)
        high = np.tile([float(p["max_accel"]), 1.0], n).astype(np.float32)
        return Box(low=low, high=high, dtype=np.float32)

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """Normalised speeds, positions and lanes of all vehicles."""
        n = self.initial_vehicles.num_vehicles
        return Box(low=0.0, high=1.0, shape=(3 * n,), dtype=np.float32)

    def _info(self, crash: bool) -> dict[str, Any]:
        info = super()._info(crash)
        info["lane_changes"] = self.k.vehicle.num_lane_changes  # all cars', this episode
        return info

    def get_state(self) -> Any:
        """Speeds, positions and lanes, normalised to [0, 1]."""
        vk, net = self.k.vehicle, self.k.network
        order = self._order()
        n = self.initial_vehicles.num_vehicles
        lanes = max(net.num_lanes(e) for e in net.get_edge_list())
        speed = fit(vk.speed[order] / net.max_speed(), n)
        pos = fit(vk.position[order] / net.length(), n)
        lane = fit(vk.lanes[order] / lanes, n)
        return clip_unit(np.concatenate([speed, pos, lane]))

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Desired velocity minus 0.1 per RL lane change (mean speed when evaluating)."""
        reward = super().compute_reward(rl_actions, **kwargs)
        if self.env_params.evaluate:
            return reward
        vk = self.k.vehicle
        changes = sum(1 for v in vk.get_rl_ids() if vk.get_last_lc(v) == self.time_counter)
        penalty = -LANE_CHANGE_PENALTY * changes if changes else 0.0
        self.reward_terms = {**self.reward_terms, "lane_change_penalty": penalty}
        return reward + penalty

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        vk = self.k.vehicle
        rows = np.arange(vk.table.size)[self._order()]
        ids = vk.table.ids
        rl_ids = [ids[i] for i in rows[vk.table.is_rl[rows]].tolist()]
        actions = np.asarray(rl_actions, dtype=np.float64).reshape(-1)
        accel, direction = actions[::2], np.rint(actions[1::2])
        n = min(len(rl_ids), accel.size)
        if not n:
            return
        rl_ids = rl_ids[:n]
        wait = float(self.env_params.additional_params["lane_change_duration"])
        blocked = [self.time_counter <= wait + vk.get_last_lc(v) for v in rl_ids]
        vk.apply_acceleration(rl_ids, accel[:n])
        vk.apply_lane_change(rl_ids, np.where(blocked, 0.0, direction[:n]))


class LaneChangeAccelPOEnv(LaneChangeAccelEnv):
    """The partially observed version (Flow's ``LaneChangeAccelPOEnv``): each RL car sees
    only its neighbours on every lane of its edge.

    Observation: per RL car (the ``num_rl_vehicles`` placed at the start, present ones in
    :attr:`sorted_ids` order, zeros for missing ones), over the network's largest number of
    lanes: gaps to the nearest car ahead, gaps to the nearest car behind (both / network
    length; 1 with none), their speeds (/ max speed; 0 with none); then every RL car's own
    speed / max speed. All in [0, 1] (Flow divides only some of these and appends raw
    speeds; flowrun normalises all). Actions and reward as :class:`LaneChangeAccelEnv`.
    """

    DEFAULT_EXPERIMENT = "envs/ring.yaml"  # one lane (LaneChangeAccelEnv's file has two)

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        net = self.k.network
        #: the largest number of lanes of any edge (Flow's ``num_lanes``)
        self.num_lanes = max(net.num_lanes(e) for e in net.get_edge_list())
        #: the neighbours observed at the last step (Flow's ``visible``)
        self.visible: list[str] = []

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """``4 * num_lanes`` neighbour values per RL car, then the RL cars' speeds."""
        n = self.initial_vehicles.num_rl_vehicles
        return Box(low=0.0, high=1.0, shape=(4 * n * self.num_lanes + n,), dtype=np.float32)

    def get_state(self) -> Any:
        """Neighbours on every lane of each RL car, and the RL cars' speeds."""
        vk, net = self.k.vehicle, self.k.network
        length, v_max, lanes = net.length(), net.max_speed(), self.num_lanes
        n = self.initial_vehicles.num_rl_vehicles
        near = np.zeros((n, 4, lanes))
        near[:, :2] = 1.0  # RL cars missing: no car ahead / behind
        speed = np.zeros(n)
        self.visible = []
        rl_set = set(vk.get_rl_ids())
        rl_ids = [v for v in self.sorted_ids if v in rl_set][:n]
        for i, rl in enumerate(rl_ids):
            near[i] = lane_neighbours(vk, rl, lanes, length, v_max)
            speed[i] = vk.get_speed(rl) / v_max
            self.visible += [v for v in vk.get_lane_leaders(rl) + vk.get_lane_followers(rl) if v]
        obs = np.concatenate([near.reshape(-1), speed])
        return clip_unit(np.nan_to_num(obs, posinf=1.0))

    def additional_command(self) -> None:
        """Flow's: mark the neighbours the RL cars see as observed."""
        super().additional_command()
        for veh_id in self.visible:
            if veh_id in self.k.vehicle.table:
                self.k.vehicle.set_observed(veh_id)
