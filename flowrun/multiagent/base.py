"""``MultiAgentEnv``: Flow's ``MultiEnv`` as a PettingZoo ``ParallelEnv``.

The simulation is flowrun's :class:`~flowrun.envs.base.Env` (seeded reset, warm-up,
``sims_per_step``, human controllers, collision checks, step records); this class only turns
its single-agent step into PettingZoo's per-agent dictionaries.
"""

from __future__ import annotations

import logging
from abc import abstractmethod
from typing import Any

import numpy as np
import numpy.typing as npt
from gymnasium.spaces import Box
from pettingzoo import ParallelEnv

from flowrun.envs.base import Env
from flowrun.envs.ring.accel import acceleration_box
from flowrun.multiagent.agents import possible_agent_ids
from flowrun.multiagent.flow_spaces import FlowSpace, callable_space
from flowrun.multiagent.observations import NEIGHBOUR_HIGH, NEIGHBOUR_LOW

log = logging.getLogger(__name__)

Obs = npt.NDArray[np.float32]
Action = npt.NDArray[np.float32]


class MultiAgentEnv(Env, ParallelEnv[str, Obs, Action]):
    """Base of the multi-agent environments: each RL vehicle is an agent.

    Agents: the agent id is the vehicle id. ``possible_agents`` is fixed at construction: the
    RL vehicles placed at reset plus, on open networks, every id the RL inflows can produce
    within one episode (see :mod:`flowrun.multiagent.agents`). ``agents`` is the RL vehicles
    in the network now, in order of arrival; it changes as inflow AVs enter and leave.

    Spaces: every agent has the same observation and action space (subclasses define them
    as the properties :attr:`agent_observation_space` and :attr:`agent_action_space`);
    ``observation_space(agent)`` and ``action_space(agent)`` return the same objects each call.

    Step: ``step(actions)`` takes one action per live agent (a missing one leaves that car to
    SUMO for the step, as Flow; an id not in ``possible_agents`` is an error), applies them
    (clipped to the action space when ``env_params.clip_actions``) for ``sims_per_step``
    simulation steps, and returns ``observations, rewards, terminations, truncations, infos``
    keyed by the agents live at the start of the step plus those that entered during it
    (except in the step that ends the episode: a car entering then never becomes an agent).

    Termination: an agent that left the network is terminated (its observation zeros and its
    reward 0, as Flow) and leaves ``agents``; a collision terminates every agent;
    the horizon truncates every agent. Either ends the episode: ``agents`` is then empty
    and :attr:`episode_over` true. On an open network ``agents`` can also be empty in the
    middle of an episode (no AV in the network right now): keep stepping with ``{}`` until
    :attr:`episode_over`.

    Infos: each agent's info holds the environment's ``crash``, ``mean_speed``,
    ``collisions``, ``teleports``, ``time`` and ``reward_terms``.

    Subclasses implement the two space properties, :meth:`get_state` (observations of
    :attr:`agents`) and :meth:`compute_reward` (one shared float or a float per agent); the
    default :meth:`_apply_rl_actions` applies each agent's first action value as an
    acceleration. Written Flow's way, a subclass defines ``observation_space`` and
    ``action_space`` as properties instead: they then read both as Flow's properties and as
    PettingZoo's methods (``env.observation_space`` and ``env.observation_space(agent)``).
    """

    metadata = {  # noqa: RUF012 - PettingZoo's and Gymnasium's name
        "render_modes": ["rgb_array"],
        "render_fps": 10,
        "name": "flowrun_multiagent_v0",
        "is_parallelizable": True,
    }

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        episode = (self.env_params.warmup_steps + self.env_params.horizon) * max(
            1, self.env_params.sims_per_step
        )
        self.possible_agents: list[str] = possible_agent_ids(
            self.initial_vehicles,
            self.net_params.inflows,
            (episode + 1) * self.sim_step,
            self.sim_step,
        )
        self._possible = frozenset(self.possible_agents)
        self.agents: list[str] = []
        obs_space = callable_space(self.agent_observation_space)
        act_space = callable_space(self.agent_action_space)
        self.observation_spaces = dict.fromkeys(self.possible_agents, obs_space)
        self.action_spaces = dict.fromkeys(self.possible_agents, act_space)
        self._obs_space, self._act_space = obs_space, act_space
        self._finished: set[str] = set()
        self._warned: set[str] = set()
        #: whether the episode ended (collision or horizon): reset before stepping again
        self.episode_over = True

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """A subclass written Flow's way declares ``observation_space``/``action_space`` as
        properties: they become every agent's space, readable both as Flow's property and as
        PettingZoo's ``observation_space(agent)``."""
        super().__init_subclass__(**kwargs)
        for name, agent_name, stored in (
            ("observation_space", "agent_observation_space", "_obs_space"),
            ("action_space", "agent_action_space", "_act_space"),
        ):
            attr = cls.__dict__.get(name)
            if isinstance(attr, property) and attr.fget is not None:
                setattr(cls, agent_name, attr)
                setattr(cls, name, FlowSpace(attr.fget, stored))

    # ------------------------------------------------------------------ subclass hooks
    @property
    @abstractmethod
    def agent_observation_space(self) -> Box:
        """The observation space of every agent."""

    @property
    @abstractmethod
    def agent_action_space(self) -> Box:
        """The action space of every agent."""

    @abstractmethod
    def get_state(self) -> dict[str, Any]:
        """Observation of each agent in :attr:`agents`."""

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> Any:
        """A reward shared by all agents (float) or one per agent (dict); 0 by default."""
        return 0.0

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        """Apply each agent's first action value as its acceleration (cars still present)."""
        vk = self.k.vehicle
        table = vk.table
        ids = [a for a in rl_actions if a in table]
        if ids:
            vk.apply_acceleration(ids, np.array([float(rl_actions[a][0]) for a in ids]))

    # ------------------------------------------------------------------ PettingZoo API
    #: every agent's observation space: read as Flow's property (``env.observation_space``)
    #: or called as PettingZoo's method (``env.observation_space(agent)``), the same object
    observation_space = FlowSpace(lambda env: env.agent_observation_space, "_obs_space")
    #: every agent's action space, as :attr:`observation_space`
    action_space = FlowSpace(lambda env: env.agent_action_space, "_act_space")

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Obs], dict[str, dict[str, Any]]]:
        """Restart the simulation (seeded as flowrun's ``Env``) and run the warm-up.

        Returns:
            ``(observations, infos)`` of the agents in the network after the warm-up.
        """
        self.agents = []
        self._finished = set()
        _, info = super().reset(seed=seed, options=options)
        self._sync_agents()
        self.episode_over = False
        states = self.get_state()
        obs = {a: self._obs(states.get(a)) for a in self.agents}
        return obs, {a: dict(info) for a in self.agents}

    def step(  # type: ignore[override]
        self, actions: dict[str, Any] | None
    ) -> tuple[
        dict[str, Obs],
        dict[str, float],
        dict[str, bool],
        dict[str, bool],
        dict[str, dict[str, Any]],
    ]:
        """Apply one action per live agent for ``sims_per_step`` simulation steps
        (``None``: no RL action at all, as Flow's ``step(None)``; rewarded as Flow's
        ``compute_reward(None)``)."""
        if self._needs_reset or not self.k.started:
            super().step(None)  # raises ResetNeeded with the base's explanation
        unknown = [a for a in actions or () if a not in self._possible]
        if unknown:
            raise KeyError(f"actions for unknown agents {unknown}; agents now: {self.agents}")
        live = list(self.agents)
        applied = None
        if actions is not None:
            applied = {a: self._clip(actions[a]) for a in live if a in actions}
        crash = False
        first = len(self.records)
        for _ in range(self.env_params.sims_per_step):
            self._simulate(applied)
            crash = self.k.simulation.check_collision()
            if crash:
                break
        self.step_counter += 1
        left, entered = self._sync_agents()
        states = self.get_state()
        reward = self.compute_reward(applied, fail=crash)
        truncated = self.step_counter >= self.env_params.horizon
        if crash or truncated:
            # a car that entered in the step ending the episode never was an agent: it is not
            # reported (PettingZoo: an agent not in ``agents`` before was "dead last turn")
            entered = []
        keys = live + entered
        rewards = {a: self._agent_reward(reward, a, a in left) for a in keys}
        records = self.records
        shared = float(np.mean(list(rewards.values()))) if rewards else 0.0
        for i in range(first, len(records)):
            records[i].reward = shared
        terminations = {a: crash or a in left for a in keys}
        truncations = {a: truncated and not terminations[a] for a in keys}
        obs = {a: self._obs(None if a in left else states.get(a)) for a in keys}
        info = self._info(crash)
        infos = {a: dict(info) for a in keys}
        if crash or truncated:
            self._finished.update(self.agents)
            self.agents = []
            self._needs_reset = True
            self.episode_over = True
        return obs, rewards, terminations, truncations, infos

    # ------------------------------------------------------------------ bookkeeping
    def _sync_agents(self) -> tuple[set[str], list[str]]:
        """Update :attr:`agents` to the RL cars present; return (left, entered)."""
        present = []
        for veh_id in self.k.vehicle.get_rl_ids():
            if veh_id in self._possible:
                present.append(veh_id)
            elif veh_id not in self._warned:
                self._warned.add(veh_id)
                log.warning("RL vehicle %s is not a possible agent: it gets no actions", veh_id)
        here = set(present)
        left = {a for a in self.agents if a not in here}
        self._finished |= left
        known = set(self.agents)
        entered = [a for a in present if a not in known and a not in self._finished]
        self.agents = [a for a in self.agents if a in here] + entered
        return left, entered

    def _agent_reward(self, reward: Any, agent: str, gone: bool) -> float:
        if gone:
            return 0.0
        if isinstance(reward, dict):
            return float(reward.get(agent, 0.0))
        return float(reward)

    def _obs(self, value: Any) -> Obs:
        space = self._obs_space
        if value is None:
            return np.zeros(space.shape, dtype=np.float32)
        obs = np.asarray(value, dtype=np.float64).reshape(space.shape)
        return np.clip(obs, space.low, space.high).astype(np.float32)

    def _clip(self, action: Any) -> Any:
        space = self._act_space
        value = np.asarray(action, dtype=np.float64).reshape(space.shape)
        if self.env_params.clip_actions:
            value = np.clip(value, space.low, space.high)
        return value

    def clip_actions(self, rl_actions: Any) -> Any:
        """Each agent's action clipped to its space when ``env_params.clip_actions``."""
        if rl_actions is None:
            return None
        return {a: self._clip(v) for a, v in rl_actions.items()}

    def _format_obs(self, obs: Any) -> Any:
        return obs  # observations are dicts; formatted per agent by ``_obs``

    def observe_agents_neighbours(self) -> None:
        """Mark each agent's leader and follower observed (Flow's ``additional_command`` of the
        highway and I-210 envs)."""
        vk = self.k.vehicle
        for rl_id in self.agents:
            for other in (vk.get_leader(rl_id), vk.get_follower(rl_id)):
                if other:
                    vk.set_observed(other)

    def state(self) -> npt.NDArray[np.float32]:
        """Not provided: the global state is the whole traffic (see the kernel's getters)."""
        raise NotImplementedError("flowrun's multi-agent envs have no global state() array")


#: Flow's name of the multi-agent base class (``flow.envs.multiagent.MultiEnv``).
MultiEnv = MultiAgentEnv


class NeighbourAgentsEnv(MultiAgentEnv):
    """Agents that see Flow's 5-value neighbour observation and set one acceleration."""

    @property
    def agent_observation_space(self) -> Box:
        """Five normalised values (see :func:`~flowrun.multiagent.observations.neighbour_obs`)."""
        return Box(low=NEIGHBOUR_LOW, high=NEIGHBOUR_HIGH, dtype=np.float32)

    @property
    def agent_action_space(self) -> Box:
        """One acceleration, m/s^2."""
        return acceleration_box(self.env_params.additional_params, 1)
