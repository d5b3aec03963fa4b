"""``MergePOEnv``: AVs on an open highway damp the waves a merging on-ramp creates.

Flow's ``flow.envs.merge`` (Flow's merge0/1/2 benchmarks; Vinitsky et al., "Benchmarks for
reinforcement learning in mixed-autonomy traffic", CoRL 2018). RL cars enter and leave the
network; up to ``num_rl`` of them, first come first served, are observed and controlled.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.base import Env
from flowrun.envs.rewards import desired_velocity
from flowrun.envs.ring.accel import acceleration_box
from flowrun.errors import ConfigError
from flowrun.types import FloatArray

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AVs, m/s^2
    "max_accel": 3,
    # maximum deceleration of the AVs, m/s^2
    "max_decel": 3,
    # desired speed of all cars, m/s (the reward's target)
    "target_velocity": 25,
    # largest number of AVs observed and controlled at once
    "num_rl": 5,
}

#: Flow's weights of the desired-velocity term and of the time-headway penalty.
ETA_VELOCITY, ETA_HEADWAY = 1.0, 0.1
#: Flow's smallest acceptable time headway, s.
T_MIN = 1.0
#: Values per observed AV.
OBS_PER_RL = 5
#: Bounds of the five values (speed, relative leader speed, headway, relative follower
#: speed, tailway), normalised.
OBS_LOW = np.array([0.0, -1.0, 0.0, -1.0, 0.0])
OBS_HIGH = np.ones(OBS_PER_RL)


def time_headway_penalty(headways: FloatArray, speeds: FloatArray, t_min: float = T_MIN) -> float:
    """Flow's penalty of short time headways: ``sum(min((max(h/v, 0) - t_min) / t_min, 0))``.

    Args:
        headways: bumper-to-bumper gaps of the AVs that have a leader, m.
        speeds: their speeds, m/s; AVs standing still (``v <= 0``) are left out.
        t_min: smallest acceptable time headway, s.

    Returns:
        A value <= 0 (s/s): 0 when every moving AV keeps at least ``t_min``.
    """
    moving = speeds > 0
    t_headway = np.maximum(headways[moving] / speeds[moving], 0.0)
    return float(np.minimum((t_headway - t_min) / t_min, 0.0).sum())


def merge_reward(
    speeds: FloatArray,
    target_velocity: float,
    rl_headways: FloatArray,
    rl_speeds: FloatArray,
    fail: bool = False,
) -> dict[str, float]:
    """Flow's ``MergePOEnv`` reward, by term; the reward is ``max(sum of terms, 0)``.

    Args:
        speeds: speeds of all cars in the network, m/s.
        target_velocity: desired speed, m/s.
        rl_headways: gaps to their leaders of the controlled AVs that have one, m.
        rl_speeds: speeds of those AVs, m/s.
        fail: a collision happened (every term 0).

    Returns:
        ``{"desired_velocity": 1.0 * desired_velocity, "headway_penalty": 0.1 * penalty}``.
    """
    if fail:
        return {"desired_velocity": 0.0, "headway_penalty": 0.0}
    return {
        "desired_velocity": ETA_VELOCITY * desired_velocity(speeds, target_velocity),
        "headway_penalty": ETA_HEADWAY * time_headway_penalty(rl_headways, rl_speeds),
    }


class MergePOEnv(Env):
    """Partially observed merge (Flow's ``MergePOEnv``).

    AVs that enter join a first-come-first-served queue; the first ``num_rl`` of it
    (:attr:`rl_veh`) are observed and controlled, the others drive as humans until a
    controlled AV leaves the network and frees a place (Flow's ``rl_queue``/``rl_veh``).

    Observation: ``5 * num_rl`` values, 5 per controlled AV in :attr:`rl_veh` order, zeros for
    empty places. With ``V`` the network's max speed and ``L`` its length:
    ``v / V``, ``(v_leader - v) / V``, ``headway / L``, ``(v - v_follower) / V``,
    ``tailway / L``. Without a leader: ``v_leader = V`` and ``headway = L``; without a
    follower: ``v_follower = 0`` and ``tailway = L``. (Flow takes the leader's gap from
    absolute positions, ``x_lead - x - length``; that equals the kernel's bumper-to-bumper
    headway on one road but not across the merge's junction, so the headway is used.)
    Each value is clipped to its bounds, ``[0, 1]`` for speeds and gaps and ``[-1, 1]`` for
    relative speeds (Flow declared ``[0, 1]`` for all, which its relative speeds leave).
    Action: ``num_rl`` accelerations in ``[-max_decel, max_accel]`` m/s^2, the i-th for the
    i-th controlled AV; actions for empty places are ignored.
    Reward: ``max(r_v + 0.1 * sum_i min((max(h_i / v_i, 0) - 1) / 1, 0), 0)`` with ``r_v``
    the desired-velocity reward towards ``target_velocity`` over all cars and the sum over
    controlled AVs that have a leader and move (``h_i`` their headway, m; ``v_i`` speed, m/s);
    0 after a collision; the mean speed of all cars in evaluate mode. Terms in
    ``info["reward_terms"]``.
    Termination: collision; truncation: horizon.
    """

    DEFAULT_EXPERIMENT = "merge.yaml"  # Flow's merge0

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        #: leaders and followers of the controlled AVs at the last observation (Flow)
        self.leader: list[str] = []
        self.follower: list[str] = []
        super().__init__(*args, **kwargs)
        self.num_rl = self._num_rl()
        self._obs_low = np.tile(OBS_LOW, self.num_rl)
        self._obs_high = np.tile(OBS_HIGH, self.num_rl)

    def _num_rl(self) -> int:
        value = self.env_params.additional_params["num_rl"]
        if isinstance(value, bool) or not isinstance(value, int | float) or value != int(value) \
                or value < 1:  # fmt: skip
            raise ConfigError(
                f"expected a whole number of AVs >= 1, got {value!r}",
                path="env.additional_params.num_rl",
            )
        return int(value)

    @property
    def action_space(self) -> Box:  # type: ignore[override]
        """One acceleration per controlled AV place."""
        return acceleration_box(self.env_params.additional_params, self.num_rl)

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """Five values per controlled AV place (see the class docstring)."""
        return Box(
            low=self._obs_low.astype(np.float32),
            high=self._obs_high.astype(np.float32),
            dtype=np.float32,
        )

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start a new episode with no AV queued or controlled."""
        self.leader, self.follower = [], []
        return super().reset(seed=seed, options=options)

    # ------------------------------------------------------------------ the AV queue
    def update_rl_queue(self, places: int | None = None) -> None:
        """The base's AV queue with ``num_rl`` places (Flow does this in
        ``additional_command``; flowrun also before each observation, so the observation
        never holds a car that has just left)."""
        super().update_rl_queue(self.num_rl if places is None else places)

    def additional_command(self) -> None:
        """Flow's: keep the AV queue current and mark the observed neighbours."""
        self.update_rl_queue()
        self.k.vehicle.set_observed_many(self.leader + self.follower)

    # ------------------------------------------------------------------ Flow's hooks
    def _apply_rl_actions(self, rl_actions: Any) -> None:
        vk = self.k.vehicle
        actions = np.asarray(rl_actions, dtype=np.float64).reshape(-1)
        table = vk.table
        ids, accs = [], []
        for i, rl_id in enumerate(self.rl_veh[: actions.size]):
            if rl_id in table and table.is_rl[table.row(rl_id)]:  # still in the network
                ids.append(rl_id)
                accs.append(actions[i])
        if ids:
            vk.apply_acceleration(ids, np.array(accs))

    def get_state(self) -> Any:
        """Five normalised values per controlled AV, zero-padded (see the class docstring)."""
        self.update_rl_queue()
        vk = self.k.vehicle
        max_speed = self.k.network.max_speed()
        max_length = self.k.network.length()
        obs = np.zeros(OBS_PER_RL * self.num_rl)
        rows = vk.table.rows(self.rl_veh)  # the controlled AVs' rows in the kernel's arrays
        speed = vk.speed[rows]
        lead, follow = vk.leader[rows], vk.follower[rows]
        has_lead, has_follow = lead >= 0, follow >= 0
        values = np.stack(
            (
                speed / max_speed,
                (np.where(has_lead, vk.speed[lead], max_speed) - speed) / max_speed,
                np.where(has_lead, vk.headway[rows], max_length) / max_length,
                (speed - np.where(has_follow, vk.speed[follow], 0.0)) / max_speed,
                np.where(has_follow, vk.tailway[rows], max_length) / max_length,
            ),
            axis=1,
        )
        obs[: values.size] = values.reshape(-1)
        ids = vk.table.ids
        self.leader = [ids[k] for k in lead[has_lead].tolist()]
        self.follower = [ids[k] for k in follow[has_follow].tolist()]
        return np.minimum(np.maximum(obs, self._obs_low), self._obs_high)

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Flow's merge reward (the mean speed when ``env_params.evaluate``)."""
        vk = self.k.vehicle
        speeds = vk.speed
        if self.env_params.evaluate:
            return float(np.mean(speeds)) if speeds.size else 0.0
        self.update_rl_queue()
        rows = vk.table.rows(self.rl_veh)
        led = rows[vk.leader[rows] >= 0]  # controlled AVs with a leader
        terms = merge_reward(
            speeds,
            float(self.env_params.additional_params["target_velocity"]),
            vk.headway[led],
            speeds[led],
            fail=bool(kwargs.get("fail", False)),
        )
        self.reward_terms = terms
        return max(sum(terms.values()), 0.0)
