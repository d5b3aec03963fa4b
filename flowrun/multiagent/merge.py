"""``MultiAgentMergePOEnv``: each AV on the merge is an agent (Flow's multi-agent merge).

Flow's ``flow.envs.multiagent.merge``. AVs enter with the inflows and leave at the end of the
road, so ``agents`` changes during an episode. Unlike Flow's version, whose
``_apply_rl_actions`` looped over ``enumerate(...)`` pairs and so never applied an action,
the agents' accelerations are applied.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from flowrun.envs.merge import merge_reward
from flowrun.multiagent.base import NeighbourAgentsEnv
from flowrun.multiagent.observations import neighbour_obs

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AVs, m/s^2
    "max_accel": 3,
    # maximum deceleration of the AVs, m/s^2
    "max_decel": 3,
    # desired speed of all cars, m/s (the reward's target)
    "target_velocity": 25,
}


class MultiAgentMergePOEnv(NeighbourAgentsEnv):
    """Partially observed multi-agent merge (Flow's ``MultiAgentMergePOEnv``).

    Every AV in the network is an agent (there is no ``num_rl`` cap, as in Flow).

    Observation (per agent, 5 values): Flow's neighbour 5-vector ``v / V``,
    ``(v_lead - v) / V``, ``headway / L``, ``(v - v_follow) / V``, ``tailway / L`` with ``V``
    the network's max speed and ``L`` its length (see
    :func:`~flowrun.multiagent.observations.neighbour_obs`) in Flow's bounds ``[-5, 5]``.
    Action (per agent): one acceleration in ``[-max_decel, max_accel]`` m/s^2.
    Reward (shared): ``max(r_v + 0.1 * sum_i min((max(h_i / v_i, 0) - 1) / 1, 0), 0)``, ``r_v``
    the desired-velocity reward of all cars towards ``target_velocity`` and the sum over the
    AVs in the network that have a leader and move (``h_i`` headway, m; ``v_i`` speed, m/s);
    0 after a collision; the mean speed of all cars in evaluate mode. Terms in
    ``info["reward_terms"]``.
    Termination: an AV leaving the network (that agent, reward 0, zero observation), a
    collision (all agents); truncation: horizon (all agents).
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        #: leaders and followers of the agents at the last observation (Flow)
        self.leader: list[str] = []
        self.follower: list[str] = []
        super().__init__(*args, **kwargs)

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
        """Start a new episode with no observed neighbours."""
        self.leader, self.follower = [], []
        return super().reset(seed=seed, options=options)

    def additional_command(self) -> None:
        """Flow's: mark the agents' observed neighbours (coloured in the GUI)."""
        vk = self.k.vehicle
        for veh_id in self.leader + self.follower:
            if veh_id in vk.table:
                vk.set_observed(veh_id)

    def get_state(self) -> dict[str, Any]:
        """The neighbour 5-vector of each agent."""
        vk = self.k.vehicle
        max_speed, length = self.k.network.max_speed(), self.k.network.length()
        self.leader = [v for v in (vk.get_leader(a) for a in self.agents) if v]
        self.follower = [v for v in (vk.get_follower(a) for a in self.agents) if v]
        return {a: neighbour_obs(vk, a, max_speed, length) for a in self.agents}

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Flow's shared merge reward (the mean speed when evaluating)."""
        vk = self.k.vehicle
        speeds = vk.speed
        if self.env_params.evaluate:
            return float(np.mean(speeds)) if speeds.size else 0.0
        led = [v for v in vk.get_rl_ids() if vk.get_leader(v)]
        self.reward_terms = merge_reward(
            speeds,
            float(self.env_params.additional_params["target_velocity"]),
            np.array(vk.get_headway(led), dtype=np.float64),
            np.array(vk.get_speed(led), dtype=np.float64),
            fail=bool(kwargs.get("fail", False)),
        )
        return max(sum(self.reward_terms.values()), 0.0)
