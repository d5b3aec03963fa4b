"""``AccelEnv``: a central agent sets the acceleration of every RL car; all cars observed."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.base import Env
from flowrun.envs.rewards import desired_velocity

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the RL cars, m/s^2
    "max_accel": 3,
    # maximum deceleration of the RL cars, m/s^2
    "max_decel": 3,
    # desired speed of all cars, m/s (the reward's target)
    "target_velocity": 10,
    # observe cars sorted by position instead of by id
    "sort_vehicles": False,
}


def clip_unit(x: np.ndarray) -> np.ndarray:
    """``x`` clipped to [0, 1] in place (two ufuncs: cheaper than ``np.clip`` per step)."""
    np.maximum(x, 0.0, out=x)
    return np.minimum(x, 1.0, out=x)


def acceleration_box(additional_params: dict[str, Any], num_rl: int) -> Box:
    """One acceleration per RL car in ``[-|max_decel|, max_accel]`` m/s^2."""
    return Box(
        low=-abs(float(additional_params["max_decel"])),
        high=float(additional_params["max_accel"]),
        shape=(num_rl,),
        dtype=np.float32,
    )


class RingAccelBase(Env):
    """What the fully observed ring tasks share (``AccelEnv``, ``WaveAttenuationEnv``).

    Observation: ``2 * num_vehicles`` values in [0, 1]: speeds / max speed, then positions /
    network length, ordered by id (or by position when ``sort_vehicles`` is set).
    Action: one acceleration per RL car in ``[-max_decel, max_accel]`` m/s^2.
    """

    @property
    def action_space(self) -> Box:  # type: ignore[override]
        """One acceleration per RL vehicle."""
        return acceleration_box(
            self.env_params.additional_params, self.initial_vehicles.num_rl_vehicles
        )

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """Normalised speeds and positions of all vehicles."""
        return Box(
            low=0.0, high=1.0, shape=(2 * self.initial_vehicles.num_vehicles,), dtype=np.float32
        )

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        rl_ids = self.k.vehicle.get_rl_ids()
        self.k.vehicle.apply_acceleration(rl_ids, rl_actions)

    def get_state(self) -> Any:
        """Speeds / max speed and positions / length, in [0, 1]."""
        vk = self.k.vehicle
        speed, pos = vk.speed, vk.position
        if self.env_params.additional_params.get("sort_vehicles"):
            order = np.argsort(pos, kind="stable")
            speed, pos = speed[order], pos[order]
        obs = np.concatenate([speed / self.k.network.max_speed(), pos / self.k.network.length()])
        return clip_unit(obs)


class AccelEnv(RingAccelBase):
    """Fully observed ring with accelerations for the RL cars (Flow's ``AccelEnv``).

    Observation: ``2 * num_vehicles`` values in [0, 1]: speeds / max speed, then positions /
    network length, ordered by id (or by position with ``sort_vehicles``).
    Action: one acceleration per RL car in ``[-max_decel, max_accel]`` m/s^2.
    Reward: :func:`desired_velocity` towards ``target_velocity`` (mean speed in evaluate mode).
    Termination: collision; truncation: horizon.
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS

    @property
    def absolute_position(self) -> dict[str, float]:
        """Flow's ``absolute_position``: each car's start plus distance travelled, modulo the
        ring length (m) - on a ring that is its position ``get_x_by_id`` taken mod length."""
        vk = self.k.vehicle
        length = self.k.network.length()
        return {veh_id: float(vk.get_x_by_id(veh_id)) % length for veh_id in vk.get_ids()}

    def _get_abs_position(self, veh_id: str) -> float:
        """Flow's helper: :attr:`absolute_position` of one car (m)."""
        return float(self.k.vehicle.get_x_by_id(veh_id)) % self.k.network.length()

    @property
    def sorted_ids(self) -> list[str]:
        """Vehicle ids in observation order (Flow's property): by absolute position when
        ``sort_vehicles`` is set, else as ``get_ids()``."""
        ids = self.k.vehicle.get_ids()
        if self.env_params.additional_params.get("sort_vehicles"):
            return sorted(ids, key=self._get_abs_position)
        return list(ids)

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Desired-velocity reward (mean speed when ``env_params.evaluate``)."""
        speeds = self.k.vehicle.speed
        if self.env_params.evaluate:
            return float(np.mean(speeds))
        reward = desired_velocity(
            speeds,
            float(self.env_params.additional_params["target_velocity"]),
            fail=bool(kwargs.get("fail", False)),
        )
        self.reward_terms = {"desired_velocity": reward}
        return reward
