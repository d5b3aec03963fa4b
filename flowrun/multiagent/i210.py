"""Flow's ``I210MultiEnv``: every AV on the I-210 sub-network is an agent with a shared policy
(Flow's ``flow/envs/multiagent/i210.py``). Nothing in it is specific to the I-210: it runs on
any network with RL vehicles.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.flow_rewards import average_velocity
from flowrun.envs.merge import time_headway_penalty
from flowrun.envs.ring.accel import acceleration_box
from flowrun.multiagent.base import MultiAgentEnv

#: the most lanes of any I-210 edge: the lane observation is padded to this many lanes
MAX_LANES = 6

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AVs, m/s^2
    "max_accel": 1,
    # maximum deceleration of the AVs, m/s^2
    "max_decel": 1,
    # observe the leader only (3 values) instead of every lane's leader and follower (38)
    "lead_obs": True,
}

ETA_SPEED, ETA_HEADWAY = 1.0, 0.1  # Flow's weights of the reward's two terms


def lane_observation(vk: Any, rl_id: str, rl_ids: set[str]) -> np.ndarray:
    """Flow's ``state_util`` + ``veh_statistics``: per lane (padded with -1 to
    :data:`MAX_LANES`) headway / 1000, tailway / 1000, leader speed / 100, follower speed / 100,
    whether the leader and the follower are AVs; then the AV's speed / 100 and (lane + 1) / 10.
    """
    leaders, followers = vk.get_lane_leaders(rl_id), vk.get_lane_followers(rl_id)
    parts = [
        np.asarray(vk.get_lane_headways(rl_id), dtype=float) / 1000,
        np.asarray(vk.get_lane_tailways(rl_id), dtype=float) / 1000,
        np.asarray(vk.get_lane_leaders_speed(rl_id), dtype=float) / 100,
        np.asarray(vk.get_lane_followers_speed(rl_id), dtype=float) / 100,
        np.array([1.0 if v in rl_ids else 0.0 for v in leaders]),
        np.array([1.0 if v in rl_ids else 0.0 for v in followers]),
    ]
    pad = MAX_LANES - len(leaders)
    padded = [np.concatenate([p, np.full(max(pad, 0), -1.0)])[:MAX_LANES] for p in parts]
    own = np.array([vk.get_speed(rl_id) / 100.0, (vk.get_lane(rl_id) + 1) / 10.0])
    return np.concatenate([*padded, own])


class I210MultiEnv(MultiAgentEnv):
    """Each AV is an agent (Flow's ``I210MultiEnv``).

    Observation (per agent): with ``lead_obs`` (default) ``[v / 50, headway / 1000,
    v_lead / 50]`` (``v_lead`` 0 without a leader); else :func:`lane_observation` (38 values).
    Unbounded, as Flow declared them.
    Action (per agent): one acceleration in ``[-max_decel, max_accel]`` m/s^2.
    Reward (per agent): ``max(mean speed of all cars + 0.1 * min((h / v - 1) / 1, 0), 0)``,
    the penalty for its own time headway (with a leader and ``v > 0``); its speed in evaluate
    mode; 0 after a collision; none in warm-up steps.
    Termination: collision (all), leaving the network (that agent); truncation: horizon.
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS
    OPTIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = {"lead_obs": True}

    @property
    def _lead_obs(self) -> bool:
        return bool(self.env_params.additional_params.get("lead_obs", True))

    @property
    def agent_observation_space(self) -> Box:
        """3 values (``lead_obs``) or 38, unbounded."""
        size = 3 if self._lead_obs else 6 * MAX_LANES + 2
        return Box(low=-np.inf, high=np.inf, shape=(size,), dtype=np.float32)

    @property
    def agent_action_space(self) -> Box:
        """One acceleration, m/s^2."""
        return acceleration_box(self.env_params.additional_params, 1)

    def get_state(self) -> dict[str, Any]:
        """Each agent's observation (see the class docstring)."""
        vk = self.k.vehicle
        if not self._lead_obs:
            rl_ids = set(vk.get_rl_ids())
            return {a: lane_observation(vk, a, rl_ids) for a in self.agents}
        obs = {}
        for rl_id in self.agents:
            lead = vk.get_leader(rl_id)
            lead_speed = float(vk.get_speed(lead)) if lead else 0.0
            obs[rl_id] = np.array([vk.get_speed(rl_id) / 50.0,
                                   vk.get_headway(rl_id) / 1000.0, lead_speed / 50.0])  # fmt: skip
        return obs

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> Any:
        """One reward per agent (see the class docstring)."""
        if rl_actions is None:
            return {}
        vk = self.k.vehicle
        fail = bool(kwargs.get("fail", False))
        mean_speed = average_velocity(self, fail=fail)
        rewards = {}
        for rl_id in self.agents:
            speed = float(vk.get_speed(rl_id))
            if self.env_params.evaluate:
                rewards[rl_id] = speed
            elif fail:
                rewards[rl_id] = 0.0
            else:
                penalty = 0.0
                if vk.get_leader(rl_id):
                    penalty = time_headway_penalty(
                        np.array([vk.get_headway(rl_id)]), np.array([speed])
                    )
                rewards[rl_id] = max(ETA_SPEED * mean_speed + ETA_HEADWAY * penalty, 0.0)
        return rewards

    def additional_command(self) -> None:
        """Flow's: mark each agent's leader and follower observed."""
        self.observe_agents_neighbours()
