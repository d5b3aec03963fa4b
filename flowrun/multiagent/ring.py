"""Multi-agent ring tasks: every AV on the ring is an agent with a shared reward.

Flow's ``flow.envs.multiagent.ring`` (``MultiAgentWaveAttenuationPOEnv`` and
``MultiAgentAccelPOEnv``), as PettingZoo ``ParallelEnv``s.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.rewards import wave_attenuation_terms
from flowrun.envs.ring.accel import acceleration_box, desired_velocity_reward
from flowrun.envs.ring.wave_attenuation import ring_bounds
from flowrun.multiagent.base import MultiAgentEnv
from flowrun.multiagent.observations import leader_obs, neighbour_obs
from flowrun.networks.base import Network

WAVE_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AVs, m/s^2
    "max_accel": 1,
    # maximum deceleration of the AVs, m/s^2
    "max_decel": 1,
    # range the ring length is drawn from at each reset, m (null: keep the network's length)
    "ring_length": [220, 270],
}

ACCEL_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AVs, m/s^2
    "max_accel": 1,
    # maximum deceleration of the AVs, m/s^2
    "max_decel": 1,
    # desired speed of all cars, m/s (the reward's target)
    "target_velocity": 20,
}

def flat_actions(rl_actions: dict[str, Any] | None) -> np.ndarray:
    """All agents' action values in one array (empty without actions)."""
    if not rl_actions:
        return np.zeros(0)
    parts = [np.asarray(a, dtype=np.float64).reshape(-1) for a in rl_actions.values()]
    return np.concatenate(parts)


class MultiAgentWaveAttenuationPOEnv(MultiAgentEnv):
    """Each AV on a ring of redrawn length is an agent (Flow's ``MultiAgentWaveAttenuationPOEnv``).

    At every reset the ring length is drawn from the integers in ``ring_length`` (as the
    single-agent ``WaveAttenuationEnv``).

    Observation (per agent, 3 values in Flow's bounds [-5, 5]): ``v / 15``,
    ``(v_lead - v) / 15`` and the bumper-to-bumper headway divided by the largest ring length
    (``ring_length[1]``, or the ring's length when ``ring_length`` is null); a car alone on
    the ring is its own leader.
    Values are clipped to those bounds (Flow declared them without clipping).
    Action (per agent): one acceleration in ``[-max_decel, max_accel]`` m/s^2.
    Reward (shared by all agents): ``4 * mean(v) / 20 - 4 * mean(|a|)`` over all cars' speeds
    and the agents' applied accelerations; 0 after a collision; the mean speed in evaluate
    mode. Terms in ``info["reward_terms"]``.
    Termination: collision (all agents); truncation: horizon (all agents).
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = WAVE_PARAMS

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        ring_bounds(self.env_params.additional_params)  # a bad ring_length fails here

    @property
    def agent_observation_space(self) -> Box:
        """Three values in [-5, 5] (see the class docstring)."""
        return Box(low=-5.0, high=5.0, shape=(3,), dtype=np.float32)

    @property
    def agent_action_space(self) -> Box:
        """One acceleration, m/s^2."""
        return acceleration_box(self.env_params.additional_params, 1)

    def episode_network(self) -> Network:
        """The ring with a length drawn uniformly from the integers in ``ring_length``."""
        bounds = ring_bounds(self.env_params.additional_params)
        if bounds is None:
            return self.initial_network
        length = int(self.np_random.integers(bounds[0], bounds[1] + 1))
        return self.initial_network.with_params(length=length)

    def get_state(self) -> dict[str, Any]:
        """Speed, relative leader speed and headway of each agent, normalised
        (:func:`~flowrun.multiagent.observations.leader_obs`)."""
        bounds = ring_bounds(self.env_params.additional_params)
        max_length = float(bounds[1]) if bounds is not None else self.k.network.length()
        return leader_obs(self.k.vehicle, self.agents, max_length)

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Shared speed reward minus acceleration penalty (mean speed when evaluating); 0 for
        no actions (Flow's warm-up steps)."""
        if rl_actions is None:
            return 0.0
        speeds = self.k.vehicle.speed
        if self.env_params.evaluate:
            return float(np.mean(speeds)) if speeds.size else 0.0
        self.reward_terms = wave_attenuation_terms(
            speeds, flat_actions(rl_actions), bool(kwargs.get("fail", False))
        )
        return float(sum(self.reward_terms.values()))


class MultiAgentAccelPOEnv(MultiAgentEnv):
    """Each AV is an agent that sees its neighbours (Flow's ``MultiAgentAccelPOEnv``).

    Meant for networks whose cars stay (ring, figure eight), it also runs on open ones.

    Observation (per agent, 6 values in Flow's bounds [-5, 5]): ``x / L`` (position along the
    network over its length), then Flow's neighbour 5-vector ``v / V``, ``(v_lead - v) / V``,
    ``headway / L``, ``(v - v_follow) / V``, ``tailway / L`` (``V`` the network's max speed;
    see :func:`~flowrun.multiagent.observations.neighbour_obs`).
    Action (per agent): one acceleration in ``[-max_decel, max_accel]`` m/s^2.
    Reward (shared): Flow's ``desired_velocity`` of all cars towards ``target_velocity``
    (0 after a collision); the mean speed in evaluate mode.
    Termination: collision (all agents), leaving the network (that agent); truncation: horizon.
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ACCEL_PARAMS

    @property
    def agent_observation_space(self) -> Box:
        """Six values in [-5, 5] (see the class docstring)."""
        return Box(low=-5.0, high=5.0, shape=(6,), dtype=np.float32)

    @property
    def agent_action_space(self) -> Box:
        """One acceleration, m/s^2."""
        return acceleration_box(self.env_params.additional_params, 1)

    def get_state(self) -> dict[str, Any]:
        """Position and neighbour 5-vector of each agent."""
        vk = self.k.vehicle
        max_speed, length = self.k.network.max_speed(), self.k.network.length()
        return {
            rl_id: np.concatenate(
                [[vk.get_x_by_id(rl_id) / length], neighbour_obs(vk, rl_id, max_speed, length)]
            )
            for rl_id in self.agents
        }

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Shared desired-velocity reward (mean speed when evaluating)."""
        return desired_velocity_reward(self, bool(kwargs.get("fail", False)))
