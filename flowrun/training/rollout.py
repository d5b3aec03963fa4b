"""Rollouts stepped inside the env processes: the policy's numpy copy acts there, step after step.

``SubprocVecEnv`` costs two pipe round trips and two process wake-ups per step and runs the
policy in the driver between them, while the env processes wait; with a fast env (the figure
eight steps in ~0.15 ms) that loop, not SUMO, sets the pace. Here the driver sends each env
process the policy (:class:`NumpyActor`, a copy of the acting half of SB3's ``MlpPolicy``) and the
observation statistics once per rollout; :meth:`RolloutEnv.rollout` steps ``n`` times on its
own, sampling actions with its own seeded generator, and sends back the whole segment
(:class:`Segment`). The driver computes the values and log-probabilities with the torch
policy, all steps at once, and fills SB3's rollout buffer (:mod:`flowrun.training.worker_rollouts`).

Observation normalisation follows ``VecNormalize`` as closely as a process that sees only its
own env can: each process starts a rollout from the driver's statistics and updates its copy
with every observation it receives before normalising it (as ``VecNormalize`` does with the
observations of all envs); the driver then updates its statistics with all of them. With one env
that is exactly ``VecNormalize``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import gymnasium
import numpy as np

from flowrun.types import FloatArray


@dataclass(frozen=True)
class Mlp:
    """A stack of dense layers, each followed by its activation (``""`` for none)."""

    weights: tuple[FloatArray, ...]
    biases: tuple[FloatArray, ...]
    activations: tuple[str, ...]

    def __call__(self, x: FloatArray) -> FloatArray:
        """The output for one input row (or a batch of rows)."""
        x = np.asarray(x, dtype=np.float64)  # float32 @ float64 takes numpy's slow path
        for weight, bias, activation in zip(self.weights, self.biases, self.activations,
                                            strict=True):
            x = x @ weight + bias
            if activation == "tanh":
                x = np.tanh(x)
            elif activation == "relu":
                x = np.maximum(x, 0.0)
        return x


@dataclass(frozen=True)
class NumpyActor:
    """The acting half of SB3's ``MlpPolicy`` (diagonal Gaussian actions) in numpy.

    Attributes:
        mean: observation -> mean action (``mlp_extractor.policy_net`` + ``action_net``).
        log_std: the actions' log standard deviations.
        low: the action space's lower bounds (actions are clipped to them before ``step``).
        high: its upper bounds.
    """

    mean: Mlp
    log_std: FloatArray
    low: FloatArray
    high: FloatArray

    def sample(self, obs: FloatArray, rng: np.random.Generator) -> FloatArray:
        """An action drawn for ``obs`` (not clipped)."""
        mean = self.mean(obs)
        return mean + np.exp(self.log_std) * rng.standard_normal(mean.shape)


@dataclass
class ObsStats:
    """Running mean and variance of the observations (SB3's ``RunningMeanStd``) and the
    normalisation ``VecNormalize`` applies with them (``clip`` and ``epsilon`` as it has them).
    ``update`` adds one observation, with ``RunningMeanStd``'s own arithmetic."""

    mean: FloatArray
    var: FloatArray
    count: float
    clip: float
    epsilon: float
    #: ``epsilon``, ``-clip`` and ``clip`` as 0-d arrays (a ufunc converts a Python float
    #: operand at every call)
    _bounds: tuple[FloatArray, FloatArray, FloatArray] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._bounds = (np.array(float(self.epsilon)), np.array(-float(self.clip)),
                        np.array(float(self.clip)))  # fmt: skip

    def update(self, obs: FloatArray) -> None:
        """Add one observation."""
        # the counts as 0-d arrays: a ufunc converts a Python float operand at every call
        count, total = np.array(self.count, np.float64), np.array(self.count + 1, np.float64)
        delta = obs - self.mean
        self.mean = self.mean + delta / total
        self.var = (self.var * count + np.square(delta) * count / total) / total
        self.count = self.count + 1

    def normalize(self, obs: FloatArray) -> FloatArray:
        """``VecNormalize.normalize_obs`` of one observation (float32)."""
        epsilon, low, high = self._bounds
        scaled = (obs - self.mean) / np.sqrt(self.var + epsilon)
        return np.minimum(np.maximum(scaled, low), high).astype(np.float32)


@dataclass
class Segment:
    """One env's ``n`` steps of a rollout; the driver adds SB3's values and log-probabilities.

    Attributes:
        obs: the observation each action was chosen on, normalised (n, obs_dim), float32.
        next_obs: the raw observation after each step (after the reset when an episode
            ended), which the driver adds to its statistics (n, obs_dim).
        actions: the sampled actions, before clipping (n, action_dim), float32.
        rewards: the env's rewards (n,).
        dones: whether the episode ended at each step (n,).
        timeouts: ``{step: last observation, normalised}`` of the episodes cut by their time
            limit (SB3 bootstraps their reward with its value).
        episodes: ``(step, info)`` for each episode that ended (``info`` with ``Monitor``'s
            ``episode`` entry).
        last_obs: the normalised observation the next rollout starts from.
        policy_s: seconds spent on the policy and the normalisation in the env process.
    """

    obs: np.ndarray
    next_obs: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    dones: np.ndarray
    timeouts: dict[int, np.ndarray] = field(default_factory=dict)
    episodes: list[tuple[int, dict[str, Any]]] = field(default_factory=list)
    last_obs: np.ndarray = field(default_factory=lambda: np.empty(0, np.float32))
    policy_s: float = 0.0


class RolloutEnv(gymnasium.Wrapper):
    """The outermost wrapper of an env process's env: remembers the last observation and
    steps whole rollout segments (:meth:`rollout`) on request.

    Args:
        env: the env (in its ``Monitor``).
        rank: the env's index in the vectorised env (its action samples' seed).
    """

    def __init__(self, env: gymnasium.Env[Any, Any], rank: int) -> None:
        super().__init__(env)
        self.rank = rank
        self._obs: np.ndarray | None = None

    def reset(self, **kwargs: Any) -> Any:
        """Reset, remembering the observation."""
        obs, info = self.env.reset(**kwargs)
        self._obs = obs
        return obs, info

    def step(self, action: Any) -> Any:
        """Step, remembering the observation."""
        result = self.env.step(action)
        self._obs = result[0]
        return result

    def rollout(
        self, policy: NumpyActor, stats: ObsStats | None, n_steps: int, entropy: tuple[int, ...]
    ) -> Segment:
        """Step ``n_steps`` times with actions sampled from ``policy``, resetting at episode
        ends as ``SubprocVecEnv`` does; the samples' generator is seeded with
        ``(*entropy, rank)``. ``stats`` (``None``: observations not normalised) is updated
        with each observation received."""
        if self._obs is None:
            raise RuntimeError("rollout before reset: reset the env first")
        rng = np.random.default_rng([*entropy, self.rank])
        raw = np.asarray(self._obs, dtype=np.float64)
        obs_dim, act_dim = raw.shape[0], policy.log_std.shape[0]
        seg = Segment(
            obs=np.empty((n_steps, obs_dim), np.float32),
            next_obs=np.empty((n_steps, obs_dim), np.float64),
            actions=np.empty((n_steps, act_dim), np.float32),
            rewards=np.empty(n_steps, np.float64),
            dones=np.zeros(n_steps, bool),
        )
        obs = _normalized(raw, stats)
        for t in range(n_steps):
            start = time.perf_counter()
            action = policy.sample(obs, rng)
            seg.obs[t], seg.actions[t] = obs, action
            clipped = np.minimum(np.maximum(action, policy.low), policy.high).astype(np.float32)
            seg.policy_s += time.perf_counter() - start
            raw, seg.rewards[t], terminated, truncated, info = self.env.step(clipped)
            final = None
            if terminated or truncated:
                seg.dones[t] = True
                seg.episodes.append((t, info))
                if truncated and not terminated:
                    final = np.asarray(raw, np.float64)
                raw, _ = self.env.reset()
            raw = np.asarray(raw, dtype=np.float64)
            seg.next_obs[t] = raw
            start = time.perf_counter()
            if stats is not None:
                stats.update(raw)  # as VecNormalize: the statistics first, then normalise
            obs = _normalized(raw, stats)
            if final is not None:
                seg.timeouts[t] = _normalized(final, stats)
            seg.policy_s += time.perf_counter() - start
        self._obs = raw
        seg.last_obs = obs
        return seg


def _normalized(obs: FloatArray, stats: ObsStats | None) -> FloatArray:
    return obs.astype(np.float32) if stats is None else stats.normalize(obs)
