"""flowrun's environments as RLlib sees them, built inside each env runner process.

Single-agent envs are flowrun's Gymnasium envs as they are. A multi-agent env (a PettingZoo
``ParallelEnv`` of :mod:`flowrun.multiagent`) is wrapped in :class:`RLlibMultiAgentEnv`, which
ends RLlib's episode on the env's ``episode_over`` and nowhere else (RLlib's own PettingZoo
wrapper, and RLlib's episode itself, end it when no agent is left, which on an open network
also happens mid-episode).
"""

from __future__ import annotations

import re
from dataclasses import replace
from typing import Any

import numpy as np
from gymnasium.spaces import Box
from ray.rllib.env.multi_agent_env import MultiAgentEnv

from flowrun.config.dump import config_to_dict
from flowrun.config.model import ExperimentConfig
from flowrun.config.vehicles import is_rl
from flowrun.envs.factory import make_env
from flowrun.loading.loader import config_from_dict
from flowrun.training.rllib.options import EPISODE_AGENT

#: The name flowrun's env creator is registered under with Ray Tune's registry.
ENV_NAME = "flowrun_env"
#: The module id of a single-agent policy (RLlib's default).
DEFAULT_MODULE = "default_policy"


def env_config_of(cfg: ExperimentConfig, evaluate: bool = False) -> dict[str, Any]:
    """Plain data an env runner rebuilds ``cfg``'s env from (``evaluate``: Flow's eval mode)."""
    if evaluate:
        cfg = replace(cfg, env=replace(cfg.env, evaluate=True))
    return {"config": config_to_dict(cfg), "source": cfg.source}


def config_of(env_config: dict[str, Any]) -> ExperimentConfig:
    """The experiment an env config describes (the inverse of :func:`env_config_of`)."""
    source = env_config.get("source")
    cfg = config_from_dict(env_config["config"], source or "<rllib env_config>")
    return replace(cfg, source=source)


def is_multiagent(env: Any) -> bool:
    """Whether ``env`` is one of flowrun's PettingZoo multi-agent envs."""
    return getattr(env, "possible_agents", None) is not None and hasattr(env, "episode_over")


def create_env(env_config: dict[str, Any]) -> Any:
    """RLlib's env creator: the config's env, multi-agent ones wrapped for RLlib."""
    env = make_env(config_of(dict(env_config)))
    return RLlibMultiAgentEnv(env) if is_multiagent(env) else env


def register() -> None:
    """Register :func:`create_env` as :data:`ENV_NAME` with Ray (idempotent)."""
    from ray.tune.registry import register_env

    register_env(ENV_NAME, create_env)


class RLlibMultiAgentEnv(MultiAgentEnv):
    """A flowrun PettingZoo ``ParallelEnv`` as an RLlib ``MultiAgentEnv``.

    The agent ids, spaces and per-agent dictionaries are the PettingZoo env's: an inflow AV
    joins with its first observation, and leaves with ``terminated`` (its last observation
    zeros and its reward 0, as Flow). RLlib's episode ends when the env's ``episode_over``
    turns true: ``terminateds["__all__"]`` after a collision (or an episode that ended before
    its horizon), ``truncateds["__all__"]`` at the horizon. Steps without agents (an open
    network with no AV in it) go on with ``{}``.

    RLlib 2.60 also ends a multi-agent episode as soon as every agent it has seen is done --
    at the first step of a merge episode whose AVs enter later, or whenever the last AV on the
    road leaves -- and goes on with the same env in a new episode, so its episode returns
    and lengths would be cut in pieces. One more agent, :data:`EPISODE_AGENT` (no vehicle),
    keeps RLlib's episode as long as the env's: it observes at reset, acts once (its action
    is ignored), and observes again only at the episode's end, with reward 0. Its module is
    never trained; it adds one agent step per episode.
    """

    #: The episode agent's observation and action (one value each, always 0 / ignored).
    EPISODE_OBS_SPACE = Box(0.0, 1.0, (1,), np.float32)
    EPISODE_ACT_SPACE = Box(-1.0, 1.0, (1,), np.float32)

    def __init__(self, env: Any) -> None:
        super().__init__()
        self.env = env
        self.possible_agents = [*env.possible_agents, EPISODE_AGENT]
        self.agents: list[Any] = []
        self.observation_spaces = {a: env.observation_space(a) for a in env.possible_agents}
        self.action_spaces = {a: env.action_space(a) for a in env.possible_agents}
        self.observation_spaces[EPISODE_AGENT] = self.EPISODE_OBS_SPACE
        self.action_spaces[EPISODE_AGENT] = self.EPISODE_ACT_SPACE

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[Any, Any], dict[Any, Any]]:
        """Reset the wrapped env; the episode agent observes."""
        obs, infos = self.env.reset(seed=seed, options=options)
        self.agents = [*self.env.agents, EPISODE_AGENT]
        return {**obs, EPISODE_AGENT: self._episode_obs()}, {**infos, EPISODE_AGENT: {}}

    def step(self, action_dict: dict[Any, Any]) -> tuple[Any, Any, Any, Any, Any]:
        """Step the wrapped env; add RLlib's ``__all__`` flags from ``episode_over`` (and the
        episode agent's last observation at the end)."""
        actions = {a: v for a, v in action_dict.items() if a != EPISODE_AGENT}
        obs, rewards, terminateds, truncateds, infos = self.env.step(actions)
        over = bool(self.env.episode_over)
        crash = any(bool(i.get("crash")) for i in infos.values())
        horizon = self.env.step_counter >= self.env.env_params.horizon
        ended = over and (crash or not horizon)
        terminateds = {**terminateds, "__all__": ended}
        truncateds = {**truncateds, "__all__": over and not ended}
        self.agents = [*self.env.agents, EPISODE_AGENT]
        if over:
            self.agents = []
            obs[EPISODE_AGENT] = self._episode_obs()
            rewards[EPISODE_AGENT] = 0.0
            terminateds[EPISODE_AGENT] = ended
            truncateds[EPISODE_AGENT] = not ended
            infos[EPISODE_AGENT] = {}
        return obs, rewards, terminateds, truncateds, infos

    def close(self) -> None:
        """Close the wrapped env (its SUMO)."""
        self.env.close()

    def _episode_obs(self) -> np.ndarray:
        return np.zeros(1, dtype=np.float32)


def _module_id(name: str) -> str:
    """A policy id safe as a folder name in RLlib's checkpoints."""
    return re.sub(r"[^A-Za-z0-9_-]", "_", name) or "policy"


def agent_groups(cfg: ExperimentConfig, agents: list[str]) -> dict[str, str]:
    """The group of each agent: its vehicle group (placed AVs ``{group}_{i}``, inflow AVs the
    inflow's vehicle type), or ``traffic_lights`` for an agent that is no vehicle."""
    placed = {
        f"{g.veh_id}_{i}": g.veh_id
        for g in cfg.vehicles.groups
        if is_rl(g)
        for i in range(g.num_vehicles)
    }
    flows: dict[str, str] = {}
    inflows = cfg.network.net_params.inflows
    if inflows is not None:
        for flow, flow_id in zip(inflows.flows, inflows.sumo_ids(), strict=True):
            flows[flow_id] = flow.veh_type
    groups = {}
    for agent in agents:
        if agent in placed:
            groups[agent] = placed[agent]
        elif agent.rpartition(".")[0] in flows:
            groups[agent] = flows[agent.rpartition(".")[0]]
        else:
            groups[agent] = "traffic_lights"
    return groups


def policy_mapping(cfg: ExperimentConfig, agents: list[str], mode: str) -> dict[str, str]:
    """Agent id -> policy id for ``train.policies`` ``shared``, ``group`` or ``agent``."""
    if mode == "shared":
        return dict.fromkeys(agents, "shared")
    if mode == "group":
        return {a: _module_id(g) for a, g in agent_groups(cfg, agents).items()}
    return {a: _module_id(a) for a in agents}


def probe_agents(cfg: ExperimentConfig) -> list[str] | None:
    """The ``possible_agents`` of ``cfg``'s env (``None`` for a single-agent env).

    Builds the env without starting SUMO (construction does not start a simulation).
    """
    env = make_env(cfg)
    try:
        return list(getattr(env, "possible_agents", [])) if is_multiagent(env) else None
    finally:
        env.close()


def as_float32(obs: Any) -> np.ndarray:
    """An observation as the float32 batch of one RLlib modules take."""
    return np.asarray(obs, dtype=np.float32)[None, ...]
