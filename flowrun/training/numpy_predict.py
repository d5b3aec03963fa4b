"""ARS's candidates acting with a numpy copy of their policy in sb3-contrib's ``AsyncEval``.

``AsyncEval``'s workers load each candidate's weights into the policy
(``load_from_vector``) and run ``evaluate_policy``, which calls ``policy.predict`` at every
step: about 0.1 ms of torch for a linear policy, as long as a figure-eight step. A
:class:`NumpyPredictor` given to ``AsyncEval`` instead of the policy loads the weights into the
torch policy and into a numpy copy, and answers ``predict`` with the copy (the torch policy
when the copy cannot be made: a discrete action space, a layer other than Linear, Tanh, ReLU).
:class:`LeanAsyncEval` goes further: its workers play the episodes on the env itself.

This module imports sb3-contrib at import time (as :mod:`flowrun.training.ars`, its user).
"""

from __future__ import annotations

import multiprocessing as mp
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from sb3_contrib.common.vec_env.async_eval import AsyncEval
from stable_baselines3.common.running_mean_std import RunningMeanStd
from stable_baselines3.common.vec_env.base_vec_env import CloudpickleWrapper

from flowrun.training.deps import require
from flowrun.training.rollout import Mlp, ObsStats

ACTIVATIONS = {"Tanh": "tanh", "ReLU": "relu"}


def mlp_of(modules: list[Any]) -> Mlp | None:
    """The numpy copy of a sequence of torch ``Linear`` / ``Tanh`` / ``ReLU`` modules (a
    ``Linear`` without bias gets a zero one), or ``None`` for any other sequence."""
    nn = require("torch").nn
    weights: list[np.ndarray] = []
    biases: list[np.ndarray] = []
    activations: list[str] = []
    for module in modules:
        if isinstance(module, nn.Linear):
            weight = module.weight.detach().cpu().numpy().astype(np.float64)
            weights.append(weight.T.copy())
            bias = module.bias
            biases.append(np.zeros(weight.shape[0]) if bias is None
                          else bias.detach().cpu().numpy().astype(np.float64).copy())
            activations.append("")
        elif type(module).__name__ in ACTIVATIONS and activations and not activations[-1]:
            activations[-1] = ACTIVATIONS[type(module).__name__]
        else:
            return None
    return Mlp(tuple(weights), tuple(biases), tuple(activations)) if weights else None


class NumpyPredictor:
    """An ARS policy's ``predict`` in numpy, for ``AsyncEval``'s workers (picklable).

    Args:
        policy: sb3-contrib's ``ARSPolicy`` (``LinearPolicy`` or ``MlpPolicy``).
    """

    def __init__(self, policy: Any) -> None:
        self.policy = policy
        self._net: Mlp | None = None
        #: for one observation of the policy's shape (the workers' case): that shape, the
        #: action bounds as floats and the action's dtype (``None``: no numpy copy, a
        #: squashed output, or actions not a vector)
        self._one: tuple[tuple[int, ...], list[tuple[float, float]], Any] | None = None
        self._refresh()

    def load_from_vector(self, vector: Any) -> None:
        """Load a candidate's weights (as ``BasePolicy.load_from_vector``)."""
        self.policy.load_from_vector(vector)
        self._refresh()

    def _refresh(self) -> None:
        spaces = require("gymnasium").spaces
        torch_layers = require("stable_baselines3.common.torch_layers")
        policy = self.policy
        box = isinstance(policy.action_space, spaces.Box)
        flat = isinstance(policy.features_extractor, torch_layers.FlattenExtractor)
        net = getattr(policy, "action_net", None)
        self._net = mlp_of(list(net)) if box and flat and net is not None else None
        self._one = None
        space = policy.action_space
        if self._net is not None and not policy.squash_output and len(space.shape) == 1:
            low = np.asarray(space.low, np.float64).tolist()
            high = np.asarray(space.high, np.float64).tolist()
            self._one = (policy.observation_space.shape, list(zip(low, high, strict=True)),
                         space.dtype)  # fmt: skip

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = False,
    ) -> tuple[np.ndarray, Any]:
        """``BasePolicy.predict``: the action for one observation or a batch of them."""
        one, net = self._one, self._net
        if one is not None and net is not None and isinstance(observation, np.ndarray) \
                and observation.shape == one[0]:  # fmt: skip
            # one observation: the same product as a batch of one, clipped on floats (the
            # same values: numpy's cost is per call)
            out = net(observation.reshape(1, -1)).tolist()[0]
            return np.array([lo if a < lo else (hi if a > hi else a)
                             for a, (lo, hi) in zip(out, one[1], strict=True)], one[2]), None
        if net is None or isinstance(observation, dict):
            return self.policy.predict(
                observation, state, episode_start, deterministic)
        space = self.policy.action_space
        obs = np.asarray(observation)
        batch = obs.reshape(-1, *self.policy.observation_space.shape)
        actions = net(batch.reshape(batch.shape[0], -1))
        if self.policy.squash_output:  # tanh output scaled to the bounds (unscale_action)
            actions = space.low + 0.5 * (actions + 1.0) * (space.high - space.low)
        else:
            actions = np.minimum(np.maximum(actions, space.low), space.high)
        actions = actions.astype(space.dtype).reshape((-1, *space.shape))
        if obs.shape == self.policy.observation_space.shape:
            actions = actions[0]  # one observation, one action
        return actions, None


class WorkerSpec(Protocol):
    """What :class:`LeanAsyncEval` needs of a worker's environment description."""

    @property
    def factory(self) -> Callable[[], Any]:
        """Builds the env (in its ``Monitor``)."""

    @property
    def seed(self) -> int:
        """The env's first reset seed."""

    @property
    def normalize(self) -> bool:
        """Normalise observations (statistics updated, as ``VecNormalize`` does)."""


class LeanAsyncEval(AsyncEval):
    """sb3-contrib's ``AsyncEval`` whose workers play each candidate's episodes on the env
    itself with :class:`NumpyPredictor`, instead of ``evaluate_policy`` through a
    ``DummyVecEnv`` and a ``VecNormalize`` (which cost about as much as a figure-eight step).

    The env sees the same calls (a reset before each candidate, a reset after each episode),
    the observation statistics get the same updates with ``RunningMeanStd``'s arithmetic
    (``VecNormalize``'s clip 10 and epsilon 1e-8), and a candidate's return is ``Monitor``'s,
    as ``evaluate_policy`` reports it.
    """

    def __init__(
        self,
        workers: Sequence[WorkerSpec],
        policy: Any,
        n_eval_episodes: int = 1,
        episode_seeds: CandidateSeeds | None = None,
    ) -> None:
        self.episode_seeds = episode_seeds
        ctx = mp.get_context("forkserver")
        self.waiting = False
        self.closed = False
        pipes = [ctx.Pipe() for _ in workers]
        self.remotes = [parent for parent, _ in pipes]
        self.processes = []
        for (parent, child), spec in zip(pipes, workers, strict=True):
            process = ctx.Process(
                target=_lean_worker, daemon=True,
                args=(child, parent, CloudpickleWrapper((spec, policy, n_eval_episodes))),
            )
            process.start()
            self.processes.append(process)
            child.close()

    def send_jobs(self, candidate_weights: Any, pop_size: int) -> None:
        """``AsyncEval.send_jobs``; with ``episode_seeds`` every candidate of this update
        first resets its env with the update's seed."""
        if self.episode_seeds is not None:
            seed = self.episode_seeds.next()
            for remote in self.remotes:
                remote.send(("seed_each", seed))
        super().send_jobs(candidate_weights, pop_size)


@dataclass
class CandidateSeeds:
    """The seeds of successive ARS updates' shared episodes: ``base + update``."""

    base: int
    update: int = 0

    def next(self) -> int:
        """This update's seed (then the next update's)."""
        self.update += 1
        return self.base + self.update - 1


class _Candidates:
    """One ``LeanAsyncEval`` worker's env, statistics and policy."""

    def __init__(self, spec: WorkerSpec, policy: Any, episodes: int) -> None:
        self.env = spec.factory()
        self.next_seed: int | None = spec.seed
        self.seed_each: int | None = None  # every candidate's first reset (common numbers)
        self.options: dict[str, Any] | None = None
        self.predictor = NumpyPredictor(policy)
        self.episodes = episodes
        self.stats: ObsStats | None = None
        if spec.normalize:
            dim = int(np.prod(self.env.observation_space.shape))
            self.stats = ObsStats(np.zeros(dim), np.ones(dim), 1e-4, 10.0, 1e-8)

    def reset(self) -> np.ndarray:
        kwargs = {"options": self.options} if self.options else {}
        obs, _ = self.env.reset(seed=self.next_seed, **kwargs)
        self.next_seed, self.options = None, None  # once, as DummyVecEnv
        return self._seen(obs)

    def _seen(self, obs: Any) -> np.ndarray:
        raw = np.asarray(obs, dtype=np.float64).ravel()
        if self.stats is None:
            return np.asarray(obs, dtype=np.float32)
        self.stats.update(raw)
        return self.stats.normalize(raw)

    def play(self, weights: Any) -> tuple[list[float], list[int]]:
        """The candidate's returns and lengths over ``episodes`` episodes."""
        self.predictor.load_from_vector(weights)
        returns: list[float] = []
        lengths: list[int] = []
        if self.seed_each is not None:
            self.next_seed = self.seed_each
        obs = self.reset()
        while len(returns) < self.episodes:
            action, _ = self.predictor.predict(obs)
            raw, _, terminated, truncated, info = self.env.step(action)
            if terminated or truncated:
                returns.append(float(info["episode"]["r"]))
                lengths.append(int(info["episode"]["l"]))
                raw, _ = self.env.reset()  # as DummyVecEnv does at an episode's end
            obs = self._seen(raw)
        return returns, lengths

    def rms(self) -> RunningMeanStd | None:
        if self.stats is None:
            return None
        rms = RunningMeanStd(shape=self.stats.mean.shape)
        rms.mean, rms.var = self.stats.mean.copy(), self.stats.var.copy()
        rms.count = self.stats.count
        return rms

    def sync(self, rms: RunningMeanStd) -> None:
        if self.stats is not None:
            self.stats = ObsStats(rms.mean.copy(), rms.var.copy(), float(rms.count), 10.0, 1e-8)


def _lean_worker(remote: Any, parent: Any, payload: CloudpickleWrapper) -> None:
    """``AsyncEval``'s worker protocol (eval, seed, set_options, get/sync_obs_rms, close)."""
    parent.close()
    spec, policy, episodes = payload.var
    worker = _Candidates(spec, policy, episodes)
    while True:
        try:
            cmd, data = remote.recv()
        except (EOFError, KeyboardInterrupt):
            break
        if cmd == "eval":
            remote.send([(index, worker.play(weights.cpu())) for index, weights in data])
        elif cmd == "seed_each":
            worker.seed_each = data
        elif cmd == "seed":
            worker.next_seed = data
            remote.send([data])
        elif cmd == "set_options":
            worker.options = data
            remote.send(None)
        elif cmd == "get_obs_rms":
            remote.send(worker.rms())
        elif cmd == "sync_obs_rms":
            worker.sync(data)
        elif cmd == "close":
            worker.env.close()
            remote.close()
            break
        else:
            raise NotImplementedError(f"{cmd!r} is not a LeanAsyncEval worker command")
