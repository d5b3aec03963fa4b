"""``LaneChangeAccelEnv``: RL cars choose accelerations and lane changes on a multi-lane ring."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.ring.accel import AccelEnv, clip_unit

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the RL cars, m/s^2
    "max_accel": 3,
    # maximum deceleration of the RL cars, m/s^2
    "max_decel": 3,
    # minimum time between two lane changes of one RL car, s
    "lane_change_duration": 5,
    # desired speed of all cars, m/s
    "target_velocity": 10,
    # observe cars sorted by position instead of by id
    "sort_vehicles": False,
}


LANE_CHANGE_PENALTY = 0.1  # reward lost per RL lane change (Flow: 10% of the best reward)


class LaneChangeAccelEnv(AccelEnv):
    """Multi-lane ring with acceleration and lane-change actions (Flow's ``LaneChangeAccelEnv``).

    Observation: ``3 * num_vehicles`` values in [0, 1]: speeds / max speed, positions /
    length, lanes / number of lanes (Flow's normalisation).
    Action: per RL car an acceleration in ``[-max_decel, max_accel]`` and a lane-change
    direction in ``[-1, 1]`` (rounded: -1 right, 0 stay, +1 left), interleaved
    ``[a_0, d_0, a_1, d_1, ...]``. A car changes lane at most every ``lane_change_duration`` s
    (Flow counts this in steps; flowrun in seconds).
    Reward: desired velocity, as :class:`AccelEnv`, minus 0.1 for every RL car that changed
    lane during the step (terms ``desired_velocity`` and ``lane_change_penalty`` in ``info``).
    """

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

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start a new episode; lane-change timers restart with the simulation clock."""
        self._last_lane_change: dict[str, float] = {}
        self._rl_lanes: np.ndarray | None = None
        obs, info = super().reset(seed=seed, options=options)
        self._rl_lanes = self._current_rl_lanes()
        return obs, info

    def _current_rl_lanes(self) -> np.ndarray:
        vk = self.k.vehicle
        return np.array(vk.get_lane(vk.get_rl_ids()), dtype=np.int64)

    def get_state(self) -> Any:
        """Speeds, positions and lanes, normalised to [0, 1]."""
        ids = self.sorted_ids
        vk = self.k.vehicle
        lanes = max(self.k.network.num_lanes(e) for e in self.k.network.get_edge_list())
        speed = np.array(vk.get_speed(ids)) / self.k.network.max_speed()
        pos = np.array([vk.get_x_by_id(v) for v in ids]) / self.k.network.length()
        lane = np.array(vk.get_lane(ids), dtype=np.float64) / lanes
        return clip_unit(np.concatenate([speed, pos, lane]))

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Desired velocity minus 0.1 per RL lane change (mean speed when evaluating)."""
        reward = super().compute_reward(rl_actions, **kwargs)
        lanes = self._current_rl_lanes()
        before = self._rl_lanes
        changes = 0 if before is None else int(np.count_nonzero(lanes != before))
        self._rl_lanes = lanes
        if self.env_params.evaluate:
            return reward
        penalty = -LANE_CHANGE_PENALTY * changes if changes else 0.0
        self.reward_terms = {**self.reward_terms, "lane_change_penalty": penalty}
        return reward + penalty

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        actions = np.asarray(rl_actions, dtype=np.float64).reshape(-1)
        accel, direction = actions[::2], np.rint(actions[1::2])
        vk = self.k.vehicle
        rl_ids = vk.get_rl_ids()
        now = self.k.simulation.time
        wait = float(self.env_params.additional_params["lane_change_duration"])
        last = self._last_lane_change
        allowed = [now - last.get(v, -np.inf) >= wait for v in rl_ids]
        direction = np.where(allowed, direction, 0.0)
        for vid, d in zip(rl_ids, direction, strict=True):
            if d != 0:
                last[vid] = now
        vk.apply_acceleration(rl_ids, accel)
        vk.apply_lane_change(rl_ids, direction)
