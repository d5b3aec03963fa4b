"""ARS (Augmented Random Search, sb3-contrib) as ``flowrun train`` runs it.

ARS is not a rollout-buffer algorithm: each update samples ``n_delta`` random directions of
the policy's weights, runs one episode (``n_eval_episodes``) with the weights moved each way
(``2 * n_delta`` candidates) and steps along the directions of the ``n_top`` best, scaled by
``learning_rate`` over the spread of their returns; ``delta_std`` is the size of the moves.
``LinearPolicy`` is the paper's linear policy (``MlpPolicy`` an MLP).

Candidates run in parallel: ``train.n_envs`` worker processes (sb3-contrib's ``AsyncEval``),
each with one environment of its own, seeded ``seed + rank`` (its ``Monitor`` file
``monitor/env_<rank>``). With ``train.normalize`` each worker normalises observations (never
rewards: candidates are ranked by their raw returns) and the statistics are merged after every
update, as in ARS V2. The model's own environment only provides the spaces and the merged
statistics; it is never stepped.

This module imports sb3-contrib at import time: reach it through
:func:`flowrun.training.algorithms.algorithm_class` (which says how to install the extra).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import sb3_contrib
from sb3_contrib.common.vec_env.async_eval import AsyncEval
from stable_baselines3.common.running_mean_std import RunningMeanStd
from stable_baselines3.common.type_aliases import MaybeCallback
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecNormalize

from flowrun.config.model import ExperimentConfig
from flowrun.training.numpy_predict import CandidateSeeds, LeanAsyncEval
from flowrun.training.vecenv import EnvFactory

SelfARS = TypeVar("SelfARS", bound="ARS")


class ARS(sb3_contrib.ARS):
    """sb3-contrib's ARS that stops between two updates once ``should_stop()`` is true.

    (sb3-contrib's own loop ignores a callback's request to stop.) Saved models load with
    either class.
    """

    should_stop: Callable[[], bool] | None = None

    def learn(  # type: ignore[override]
        self: SelfARS,
        total_timesteps: int,
        callback: MaybeCallback = None,
        log_interval: int = 1,
        tb_log_name: str = "ARS",
        reset_num_timesteps: bool = True,
        async_eval: AsyncEval | None = None,
        progress_bar: bool = False,
    ) -> SelfARS:
        """sb3-contrib's ``ARS.learn``, checking ``should_stop`` before each update."""
        total, callback = self._setup_learn(
            total_timesteps, callback, reset_num_timesteps, tb_log_name, progress_bar
        )
        callback.on_training_start(locals(), globals())
        try:
            while self.num_timesteps < total and not self._stopping():
                self._update_current_progress_remaining(self.num_timesteps, total_timesteps)
                self._do_one_update(callback, async_eval)
                if log_interval is not None and self._n_updates % log_interval == 0:
                    self.dump_logs()
        finally:
            if async_eval is not None:
                async_eval.close()
        callback.on_training_end()
        return self

    def _excluded_save_params(self) -> list[str]:
        """``should_stop`` belongs to the running process, never to the saved model."""
        excluded: list[str] = super()._excluded_save_params()
        return [*excluded, "should_stop"]

    def _stopping(self) -> bool:
        return self.should_stop is not None and self.should_stop()


@dataclass(frozen=True)
class WorkerEnv:
    """Picklable ``() -> VecEnv`` for one ``AsyncEval`` worker: one env, seeded, normalised.

    Attributes:
        factory: builds the env (in its ``Monitor``).
        seed: the env's first reset seed (later resets continue its generator).
        normalize: wrap in ``VecNormalize`` (observations only, statistics updated).
    """

    factory: EnvFactory
    seed: int
    normalize: bool

    def __call__(self) -> VecEnv:
        """Build the worker's environment (in the worker process)."""
        venv: VecEnv = DummyVecEnv([self.factory])
        venv.seed(self.seed)
        if self.normalize:
            venv = VecNormalize(venv, training=True, norm_obs=True, norm_reward=False)
        return venv


def async_eval(
    model: ARS,
    cfg: ExperimentConfig,
    n_workers: int,
    seed: int,
    normalize: bool,
    monitor_dir: Path | None,
) -> AsyncEval:
    """``n_workers`` processes evaluating ``model``'s candidates (forkserver, as the envs).

    Worker ``rank``'s env is seeded ``seed + rank``; with ``normalize`` the workers start from
    the model's observation statistics (a resumed run's included). With
    ``train.common_random_numbers`` every candidate of update ``k`` resets its env with seed
    ``seed + 20000 + k``.
    """
    workers: list[WorkerEnv] = [
        WorkerEnv(
            EnvFactory(cfg, None if monitor_dir is None else str(monitor_dir / f"env_{rank}")),
            seed + rank,
            normalize,
        )
        for rank in range(n_workers)
    ]
    # the workers play the episodes on their env with a numpy copy of each candidate
    tc = cfg.train
    shared = tc is not None and tc.common_random_numbers
    evaluator = LeanAsyncEval(
        workers, model.policy, n_eval_episodes=model.n_eval_episodes,
        episode_seeds=CandidateSeeds(seed + 20_000, model._n_updates) if shared else None,
    )
    stats = model.get_vec_normalize_env()
    if normalize and stats is not None and isinstance(stats.obs_rms, RunningMeanStd):
        evaluator.sync_obs_rms(stats.obs_rms.copy())
        model.old_count = stats.obs_rms.count
    return evaluator


def learn_kwargs(
    model: Any,
    cfg: ExperimentConfig,
    n_workers: int,
    seed: int,
    normalize: bool,
    monitor_dir: Path | None,
    should_stop: Callable[[], bool],
) -> dict[str, Any]:
    """What ``model.learn`` needs beyond SB3's usual arguments: the parallel evaluator."""
    model.should_stop = should_stop
    return {"async_eval": async_eval(model, cfg, n_workers, seed, normalize, monitor_dir)}
