"""Flow's ``MultiWaveAttenuationPOEnv``: one AV per ring of a
:class:`~flowrun.networks.multi_ring.MultiRingNetwork`, each an agent rewarded for the traffic
on its own ring ("lord of the rings", Flow's ``flow/envs/multiagent/ring/wave_attenuation.py``).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.ring.accel import acceleration_box
from flowrun.multiagent.base import MultiAgentEnv
from flowrun.multiagent.observations import leader_obs

RINGS_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AVs, m/s^2
    "max_accel": 1,
    # maximum deceleration of the AVs, m/s^2
    "max_decel": 1,
    # [low, high] ring lengths, m: the headway is normalised by ``high``
    "ring_length": [230, 230],
    # desired speed of the cars of each ring, m/s (the reward's target)
    "target_velocity": 4,
}

def ring_of(edge: str) -> str:
    """The ring index in a multi-ring edge id (``top_3`` -> ``3``)."""
    return edge.rsplit("_", 1)[-1]


def ring_reward(speeds: np.ndarray, target: float) -> float:
    """Flow's desired-velocity reward of one ring's cars: ``max(|t| - |v - t|, 0) / |t|``
    with ``t`` the target speed for every car (m/s); 0 without cars."""
    if not speeds.size:
        return 0.0
    best = float(np.linalg.norm(np.full(speeds.size, target)))
    cost = float(np.linalg.norm(speeds - target))
    return max(best - cost, 0.0) / best if best > 0 else 0.0


class MultiWaveAttenuationPOEnv(MultiAgentEnv):
    """Each AV of a multi-ring network is an agent on its own ring.

    Observation (per agent, 3 values in [-1, 1]): ``v / 15``, ``(v_lead - v) / 15`` and the
    headway over ``ring_length[1]`` (a car alone on its ring is its own leader).
    Action (per agent): the accelerations of the AVs of one ring (Flow: ``num_rl /
    num_rings`` values, usually one) in ``[-max_decel, max_accel]`` m/s^2.
    Reward (per agent): :func:`ring_reward` of the cars on the agent's ring towards
    ``target_velocity``; 0 for every agent after a collision; none in warm-up steps.
    Termination: collision (all agents); truncation: horizon.
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = RINGS_PARAMS

    @property
    def agent_observation_space(self) -> Box:
        """Three values in [-1, 1]."""
        return Box(low=-1.0, high=1.0, shape=(3,), dtype=np.float32)

    @property
    def agent_action_space(self) -> Box:
        """The accelerations of one ring's AVs, m/s^2."""
        rings = int(self.net_params.additional_params.get("num_rings", 1))
        per_ring = max(1, self.initial_vehicles.num_rl_vehicles // max(1, rings))
        return acceleration_box(self.env_params.additional_params, per_ring)

    def get_state(self) -> dict[str, Any]:
        """Speed, relative leader speed and headway of each agent, normalised
        (:func:`~flowrun.multiagent.observations.leader_obs`)."""
        max_length = float(self.env_params.additional_params["ring_length"][1])
        return leader_obs(self.k.vehicle, self.agents, max_length)

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> Any:
        """Each agent's ring reward (see the class docstring)."""
        if rl_actions is None:
            return {}
        if kwargs.get("fail", False):
            return dict.fromkeys(self.agents, 0.0)
        vk = self.k.vehicle
        target = float(self.env_params.additional_params["target_velocity"])
        by_ring: dict[str, list[float]] = {}
        for veh_id in vk.get_ids():
            route = vk.get_route(veh_id)
            by_ring.setdefault(ring_of(route[0]) if route else "", []).append(
                float(vk.get_speed(veh_id))
            )
        out = {}
        for rl_id in self.agents:
            route = vk.get_route(rl_id)
            ring = ring_of(route[0]) if route else ""
            out[rl_id] = ring_reward(np.array(by_ring.get(ring, [])), target)
        return out
