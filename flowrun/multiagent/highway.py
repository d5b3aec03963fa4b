"""``MultiAgentHighwayPOEnv``: AVs on an open highway, each rewarded for its own headway.

Flow's ``flow.envs.multiagent.highway`` (acceleration only: Flow never implemented its lane
change action either).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.merge import ETA_HEADWAY, ETA_VELOCITY, time_headway_penalty
from flowrun.envs.rewards import desired_velocity
from flowrun.multiagent.base import NeighbourAgentsEnv
from flowrun.multiagent.observations import neighbour_obs

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AVs, m/s^2
    "max_accel": 1,
    # maximum deceleration of the AVs, m/s^2
    "max_decel": 1,
    # desired speed of all cars, m/s (the reward's target)
    "target_velocity": 25,
}


def highway_agent_reward(
    r_velocity: float, headway: float | None, speed: float, fail: bool = False
) -> float:
    """Flow's per-AV highway reward: ``max(r_v + 0.1 * min((max(h / v, 0) - 1) / 1, 0), 0)``.

    Args:
        r_velocity: the desired-velocity reward of all cars (shared part).
        headway: the AV's gap to its leader, m (``None`` without a leader: no penalty).
        speed: the AV's speed, m/s (no penalty when standing).
        fail: a collision happened (reward 0).
    """
    if fail:
        return 0.0
    penalty = 0.0
    if headway is not None:
        penalty = time_headway_penalty(np.array([headway]), np.array([speed]))
    return max(ETA_VELOCITY * r_velocity + ETA_HEADWAY * penalty, 0.0)


class MultiAgentHighwayPOEnv(NeighbourAgentsEnv):
    """Partially observed multi-agent highway (Flow's ``MultiAgentHighwayPOEnv``).

    Observation (per agent, 5 values): Flow's neighbour 5-vector ``v / V``,
    ``(v_lead - v) / V``, ``headway / L``, ``(v - v_follow) / V``, ``tailway / L``
    (see :func:`~flowrun.multiagent.observations.neighbour_obs`; Flow's code took the
    *leader's* headway for the third value, its docstring the AV's: the AV's is used),
    unbounded, as Flow declared them.
    Action (per agent): one acceleration in ``[-max_decel, max_accel]`` m/s^2.
    Reward (per agent): ``max(r_v + 0.1 * min((max(h / v, 0) - 1) / 1, 0), 0)`` with ``r_v``
    the desired-velocity reward of all cars towards ``target_velocity``, ``h`` the agent's
    headway (m) and ``v`` its speed (m/s), the penalty only with a leader and ``v > 0``;
    0 after a collision; the agent's own speed in evaluate mode.
    Termination: an AV leaving the network (that agent), a collision (all agents);
    truncation: horizon (all agents).
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS

    @property
    def agent_observation_space(self) -> Box:
        """Five values, unbounded (Flow's declared space)."""
        return Box(low=-np.inf, high=np.inf, shape=(5,), dtype=np.float32)

    def additional_command(self) -> None:
        """Flow's: mark each agent's leader and follower observed."""
        self.observe_agents_neighbours()

    def get_state(self) -> dict[str, Any]:
        """The neighbour 5-vector of each agent."""
        vk = self.k.vehicle
        max_speed, length = self.k.network.max_speed(), self.k.network.length()
        return {a: neighbour_obs(vk, a, max_speed, length) for a in self.agents}

    def compute_reward(  # type: ignore[override]  # one reward per agent
        self, rl_actions: Any, **kwargs: Any
    ) -> dict[str, float]:
        """Flow's reward of each agent (its speed when evaluating); ``{}`` for no actions
        (Flow's warm-up steps)."""
        if rl_actions is None:
            return {}
        vk = self.k.vehicle
        if self.env_params.evaluate:
            return {a: float(vk.get_speed(a)) for a in self.agents}
        fail = bool(kwargs.get("fail", False))
        r_v = desired_velocity(
            vk.speed, float(self.env_params.additional_params["target_velocity"]), fail=fail
        )
        self.reward_terms = {"desired_velocity": ETA_VELOCITY * r_v}
        out = {}
        for a in self.agents:
            headway = float(vk.get_headway(a)) if vk.get_leader(a) else None
            out[a] = highway_agent_reward(r_v, headway, float(vk.get_speed(a)), fail)
        return out
