"""``TestEnv``: Flow's environment for simulations without autonomy (``flow.envs.TestEnv``).

Flow's non-RL example configs run on it. It has no actions and no observations.

* Observation: ``Box(0, 0, (0,))`` — an empty array.
* Action: ``Box(0, 0, (0,))`` — none (``None`` is accepted too).
* Reward: ``env_params.additional_params["reward_fn"](env)`` when given, else 0.
* Termination: a collision (``terminated``); the horizon (``truncated``).
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium
import numpy as np

from flowrun.envs.base import Env


class TestEnv(Env):
    """An environment that only runs the human drivers (see the module docstring)."""

    DEFAULT_EXPERIMENT = "envs/ring.yaml"
    OPTIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = {"reward_fn": None}

    __test__ = False  # not a pytest test class despite its name

    @property
    def action_space(self) -> gymnasium.spaces.Box:  # type: ignore[override]
        """No actions."""
        return gymnasium.spaces.Box(low=0.0, high=0.0, shape=(0,), dtype=np.float32)

    @property
    def observation_space(self) -> gymnasium.spaces.Box:  # type: ignore[override]
        """No observations."""
        return gymnasium.spaces.Box(low=0.0, high=0.0, shape=(0,), dtype=np.float32)

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        """Nothing to apply."""

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """``additional_params["reward_fn"](self)`` if the config gives one, else 0."""
        reward_fn = self.env_params.additional_params.get("reward_fn")
        return float(reward_fn(self)) if callable(reward_fn) else 0.0

    def get_state(self, **kwargs: Any) -> np.ndarray:
        """An empty observation."""
        return np.zeros(0, dtype=np.float32)
