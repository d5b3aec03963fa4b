"""A multi-agent env seen as one joint agent, as :class:`~flowrun.experiment.runner.Experiment`
steps it (``flowrun baseline`` of a multi-agent config, ``flowrun eval`` of an RLlib run)."""

from __future__ import annotations

from typing import Any

import numpy as np


class JointView:
    """A flowrun multi-agent env with Gymnasium's single-agent step: joint observation and
    action dicts, the mean of the agents' rewards (0 while there is no agent), and the
    episode's end from the env's ``episode_over`` (``terminated`` after a collision or when
    the episode ends before the horizon, ``truncated`` at the horizon). Attributes are the
    env's."""

    def __init__(self, env: Any) -> None:
        object.__setattr__(self, "_env", env)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._env, name)

    def __setattr__(self, name: str, value: Any) -> None:
        setattr(self._env, name, value)

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        """Reset the env."""
        return self._env.reset(seed=seed, options=options)

    def step(self, actions: dict[str, Any] | None) -> tuple[Any, float, bool, bool, Any]:
        """One step; ``None`` sends no RL action at all (Flow's ``step(None)``)."""
        env = self._env
        obs, rewards, _, _, infos = env.step(actions)
        reward = float(np.mean(list(rewards.values()))) if rewards else 0.0
        over = bool(env.episode_over)
        crash = any(bool(i.get("crash")) for i in infos.values())
        terminated = over and (crash or env.step_counter < env.env_params.horizon)
        return obs, reward, terminated, over and not terminated, infos


def joint_view(env: Any) -> Any:
    """``env`` as :class:`JointView` when it is a multi-agent env (not yet a view), else
    ``env`` itself."""
    if isinstance(env, JointView) or getattr(env, "episode_over", None) is None:
        return env
    return JointView(env)
