"""Flow's ``AdversarialAccelEnv``: two agents on one fully observed network, ``av`` (the RL
cars' accelerations) and ``adversary`` (perturbations added to them), with opposite rewards
(Flow's ``flow/envs/multiagent/ring/accel.py``)."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.ring.accel import (
    ADDITIONAL_ENV_PARAMS,
    acceleration_box,
    clip_unit,
    desired_velocity_reward,
    fit,
)
from flowrun.multiagent.base import MultiAgentEnv

ADVERSARIAL_PARAMS: dict[str, Any] = {
    **ADDITIONAL_ENV_PARAMS,
    # share of the adversary's action added to the AV's: accel = av + perturb_weight * adversary
    "perturb_weight": 0.03,
}

AGENTS = ("av", "adversary")


class AdversarialAccelEnv(MultiAgentEnv):
    """The ``av`` agent drives the RL cars; the ``adversary`` perturbs its commands.

    Agents: ``av`` and ``adversary``, both present for the whole episode (not vehicle ids).
    Observation (both, the same): ``2 * num_vehicles`` values in [0, 1], speeds / the
    network's max speed then positions / its length (by position with ``sort_vehicles``),
    as ``AccelEnv``'s.
    Action (both): one value per RL car in ``[-max_decel, max_accel]``; the RL cars (in
    position order with ``sort_vehicles``) get ``av + perturb_weight * adversary`` m/s^2.
    Reward: ``av`` gets Flow's desired-velocity reward (the mean speed in evaluate mode),
    ``adversary`` its negative.
    Termination: collision; truncation: horizon (both agents).
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADVERSARIAL_PARAMS

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.possible_agents = list(AGENTS)
        self._possible = frozenset(AGENTS)
        self.observation_spaces = dict.fromkeys(AGENTS, self._obs_space)
        self.action_spaces = dict.fromkeys(AGENTS, self._act_space)

    @property
    def agent_observation_space(self) -> Box:
        """Normalised speeds and positions of all vehicles."""
        n = self.initial_vehicles.num_vehicles
        return Box(low=0.0, high=1.0, shape=(2 * n,), dtype=np.float32)

    @property
    def agent_action_space(self) -> Box:
        """One acceleration (or perturbation) per RL car, m/s^2."""
        return acceleration_box(
            self.env_params.additional_params, self.initial_vehicles.num_rl_vehicles
        )

    def _sync_agents(self) -> tuple[set[str], list[str]]:
        """Both agents from the reset to the end of the episode."""
        entered = [a for a in AGENTS if a not in self.agents]
        self.agents = list(AGENTS)
        return set(), entered

    def _order(self) -> np.ndarray:
        vk = self.k.vehicle
        rows = np.arange(vk.table.size)
        if self.env_params.additional_params.get("sort_vehicles"):
            rows = rows[np.argsort(vk.position, kind="stable")]
        return rows

    def get_state(self) -> dict[str, Any]:
        """The same observation for both agents."""
        vk, n = self.k.vehicle, self.initial_vehicles.num_vehicles
        order = self._order()
        speed = fit(vk.speed[order] / self.k.network.max_speed(), n)
        pos = fit(vk.position[order] / self.k.network.length(), n)
        state = clip_unit(np.concatenate([speed, pos]))
        return dict.fromkeys(AGENTS, state)

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        vk = self.k.vehicle
        size = self._act_space.shape[0] if self._act_space.shape else 0
        av = np.asarray(rl_actions.get("av", np.zeros(size)), dtype=np.float64).reshape(-1)
        adversary = np.asarray(rl_actions.get("adversary", np.zeros(size)), dtype=np.float64)
        weight = float(self.env_params.additional_params["perturb_weight"])
        accel = av + weight * adversary.reshape(-1)
        order = self._order()
        rl_ids = [vk.table.ids[i] for i in order[vk.table.is_rl[order]].tolist()]
        n = min(len(rl_ids), accel.size)
        if n:
            vk.apply_acceleration(rl_ids[:n], accel[:n])

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> Any:
        """``{'av': r, 'adversary': -r}``, ``r`` the desired-velocity reward."""
        reward = desired_velocity_reward(self, bool(kwargs.get("fail", False)))
        return {"av": reward, "adversary": -reward}
