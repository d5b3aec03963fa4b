"""The numpy rings as a stable-baselines3 ``VecEnv`` and as a Gymnasium vector env.

Both behave like ``num_envs`` copies of the config's SUMO env: env ``i`` is reset with seed
``seed + i`` (SB3's ``VecEnv.seed``), continues its generator at automatic resets, and
``cycle_seeds`` (for repeatable evaluations) resets with those seeds in turn. Episodes end
with ``terminated`` on a collision and ``truncated`` at the horizon. Per-step ``info`` dicts
are empty except at an episode's end, where they hold ``crash``, ``mean_speed`` (the
episode's last step) and SB3's ``terminal_observation``/``TimeLimit.truncated``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium
import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

from flowrun.fastring.plan import RingPlan
from flowrun.fastring.rings import FastRings
from flowrun.fastring.tasks import RingTask
from flowrun.types import BoolArray


class RingEpisodes:
    """``num_envs`` rings with the Gymnasium episode contract (shared by both vector envs).

    Args:
        plan: the config's facts.
        num_envs: rings stepped together.
        cycle_seeds: reset seeds each ring uses in turn (``None``: its own generator).
    """

    def __init__(
        self, plan: RingPlan, num_envs: int, cycle_seeds: Sequence[int] | None = None
    ) -> None:
        self.plan = plan
        self.num_envs = num_envs
        self.rings = FastRings(plan, num_envs)
        self.task = RingTask(plan)
        self.cycle = tuple(cycle_seeds) if cycle_seeds else None
        self.resets = np.zeros(num_envs, dtype=np.int64)
        self.started = False

    def _seeds(self, cols: np.ndarray, seeds: Sequence[int | None]) -> list[int | None]:
        if self.cycle is None:
            return list(seeds)
        out: list[int | None] = [self.cycle[int(n) % len(self.cycle)] for n in self.resets[cols]]
        return out

    def reset_all(self, seeds: Sequence[int | None]) -> np.ndarray:
        """Reset every ring (``seeds[i]`` for ring ``i``); the observations ``(B, obs)``."""
        cols = np.arange(self.num_envs)
        self.rings.reset(cols, self._seeds(cols, seeds))
        self.resets += 1
        self.started = True
        return self.task.observe(self.rings)

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, BoolArray, BoolArray, np.ndarray, np.ndarray]:
        """Step every ring and reset those whose episode ended.

        Returns:
            observations (after automatic resets), rewards, terminated, truncated, the
            final observations of the rings that ended (rows of ended rings), and the mean
            speed of every ring at this step.
        """
        if not self.started:
            raise gymnasium.error.ResetNeeded("call reset() before step()")
        applied = self.task.clip(actions)
        crashed = self.rings.step(applied)
        rewards = self.task.rewards(self.rings, applied, crashed)
        obs = self.task.observe(self.rings)
        state = self.rings.state
        assert state is not None
        mean_speed = state.speed.sum(axis=0) / state.speed.shape[0]
        truncated = self.rings.episode_steps >= self.plan.horizon
        ended = np.flatnonzero(crashed | truncated)
        final = obs[ended].copy()
        if ended.size:
            self.rings.reset(ended, self._seeds(ended, [None] * ended.size))
            self.resets[ended] += 1
            obs[ended] = self.task.observe(self.rings)[ended]
        return obs, rewards, crashed, truncated & ~crashed, final, mean_speed


class RingVecEnv(VecEnv):
    """stable-baselines3 ``VecEnv`` of ``num_envs`` numpy rings of one config.

    Args:
        plan: the config's facts (:func:`~flowrun.fastring.plan.ring_plan`).
        num_envs: rings stepped together.
        cycle_seeds: reset seeds each ring uses in turn (repeatable evaluations).
    """

    def __init__(
        self, plan: RingPlan, num_envs: int, cycle_seeds: Sequence[int] | None = None
    ) -> None:
        self.episodes = RingEpisodes(plan, num_envs, cycle_seeds)
        self.render_mode = None
        self._actions: np.ndarray | None = None
        task = self.episodes.task
        super().__init__(num_envs, task.observation_space, task.action_space)

    def reset(self) -> np.ndarray:
        """Reset every ring (with the seeds given to :meth:`seed`, if any)."""
        obs = self.episodes.reset_all(self._seeds)
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = [{} for _ in range(self.num_envs)]
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Store the actions of the next :meth:`step_wait`."""
        self._actions = actions

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        """Step every ring; rings whose episode ended are reset (SB3's auto-reset)."""
        assert self._actions is not None, "step_async() first"
        obs, rewards, terminated, truncated, final, speed = self.episodes.step(self._actions)
        dones = terminated | truncated
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for k, i in enumerate(np.flatnonzero(dones).tolist()):
            infos[i] = {
                "crash": bool(terminated[i]),
                "mean_speed": float(speed[i]),
                "terminal_observation": final[k],
                "TimeLimit.truncated": bool(truncated[i]),
            }
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        """Nothing to release (no simulator, no subprocess)."""

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The attribute of this vector env, once per index (the rings share one config)."""
        return [getattr(self, attr_name) for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set an attribute of this vector env (shared by all rings)."""
        setattr(self, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **kwargs: Any
    ) -> list[Any]:
        """Call a method of this vector env once per index."""
        method = getattr(self, method_name)
        return [method(*method_args, **kwargs) for _ in self._get_indices(indices)]

    def env_is_wrapped(
        self, wrapper_class: type[gymnasium.Wrapper], indices: VecEnvIndices = None
    ) -> list[bool]:
        """No ring is wrapped (wrap the vector env instead, e.g. ``VecMonitor``)."""
        return [False for _ in self._get_indices(indices)]


class RingVectorEnv(gymnasium.vector.VectorEnv):
    """Gymnasium vector env of ``num_envs`` numpy rings (``autoreset_mode`` ``SAME_STEP``:
    an ended ring is reset within the step; its final observation is in
    ``info["final_obs"]`` where ``info["_final_obs"]`` is true).

    Args:
        plan: the config's facts.
        num_envs: rings stepped together.
    """

    metadata = {"autoreset_mode": gymnasium.vector.AutoresetMode.SAME_STEP}  # noqa: RUF012

    def __init__(self, plan: RingPlan, num_envs: int) -> None:
        self.episodes = RingEpisodes(plan, num_envs)
        task = self.episodes.task
        self.num_envs = num_envs
        self.single_observation_space = task.observation_space
        self.single_action_space = task.action_space
        self.observation_space = gymnasium.vector.utils.batch_space(
            task.observation_space, num_envs
        )
        self.action_space = gymnasium.vector.utils.batch_space(task.action_space, num_envs)

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every ring: ``seed`` (int: ring ``i`` gets ``seed + i``) or one per ring."""
        if isinstance(seed, int):
            seeds: list[int | None] = [seed + i for i in range(self.num_envs)]
        elif seed is None:
            seeds = [None] * self.num_envs
        else:
            seeds = list(seed)
        return self.episodes.reset_all(seeds), {}

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Step every ring (rings that end are reset in the same step)."""
        obs, rewards, terminated, truncated, final, speed = self.episodes.step(np.asarray(actions))
        ended = terminated | truncated
        info: dict[str, Any] = {"mean_speed": speed, "crash": terminated}
        if ended.any():
            final_obs = np.empty(self.num_envs, dtype=object)
            for k, i in enumerate(np.flatnonzero(ended).tolist()):
                final_obs[i] = final[k]
            info["final_obs"] = final_obs
            info["_final_obs"] = ended
        return obs, rewards, terminated, truncated, info
