"""A training run's parts: the env processes, the model (new or from a checkpoint), the
episodes that pick the best model, and closing them.

:func:`flowrun.training.trainer.train` puts them together.
"""

from __future__ import annotations

import logging
import multiprocessing.forkserver
import signal
import threading
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flowrun.config.model import ExperimentConfig, TrainConfig
from flowrun.training.algorithms import build_hyperparams
from flowrun.training.callbacks import StopRequested
from flowrun.training.deps import require
from flowrun.training.numpy_eval import NumpyEpisodeRunner
from flowrun.training.periodic_eval import EpisodeRunner, Episodes
from flowrun.training.timing import TrainTiming, timed_vec_env
from flowrun.training.vecenv import make_vec_env, wrap_normalize

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.vec_env import VecEnv

log = logging.getLogger(__name__)


def learn_kwargs(
    model: BaseAlgorithm,
    cfg: ExperimentConfig,
    tc: TrainConfig,
    seed: int,
    run_dir: Path,
    stop: StopRequested,
) -> dict[str, Any]:
    """ARS evaluates its candidates in ``n_envs`` worker processes of its own
    (:mod:`flowrun.training.ars`); the other algorithms need nothing more."""
    if tc.algorithm != "ARS":
        return {}
    ars = require("flowrun.training.ars")
    kwargs: dict[str, Any] = ars.learn_kwargs(
        model, cfg, tc.n_envs, seed, tc.normalize, run_dir / "monitor", stop
    )
    return kwargs


def start_forkserver_shielded() -> None:
    """Start multiprocessing's fork server with SIGINT ignored.

    The env subprocesses are forked from it and inherit that, so Ctrl-C in a terminal (sent
    to the whole process group) reaches only this process, which stops at a step boundary and
    closes the envs itself. SIGINT stays blocked here meanwhile, so a Ctrl-C in that moment is
    delivered afterwards, not lost. SIGTERM is left alone (``multiprocessing`` ends stray
    children with it); when it reaches the envs too, training stops as interrupted all the
    same. No-op when the fork server already runs or outside the main thread.
    """
    if threading.current_thread() is not threading.main_thread():
        return
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    handler = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        multiprocessing.forkserver.ensure_running()
    finally:
        signal.signal(signal.SIGINT, handler)
        signal.pthread_sigmask(signal.SIG_SETMASK, blocked)


def training_env(
    cfg: ExperimentConfig,
    tc: TrainConfig,
    seed: int,
    run_dir: Path,
    state: dict[str, Any] | None,
    timing: TrainTiming,
) -> VecEnv:
    monitor_dir = run_dir / "monitor"
    monitor_dir.mkdir(exist_ok=True)
    # Resumed runs reseed differently so they do not replay the first episodes.
    env_seed = seed if state is None else seed + int(state["timesteps"])
    ars = tc.algorithm == "ARS"  # its workers step their own envs; this one gives the spaces
    venv = make_vec_env(
        cfg, 1 if ars else tc.n_envs, env_seed, monitor_dir=None if ars else monitor_dir,
        subprocess=True, worker_rollouts=not ars,
    )
    venv = timed_vec_env(venv, timing)
    if tc.normalize:
        stats = None
        if state is not None and state.get("vecnormalize"):
            stats = run_dir / "checkpoints" / state["vecnormalize"]
        venv = wrap_normalize(venv, stats, training=True, gamma=_gamma(tc), rewards=not ars)
    return venv


def _gamma(tc: TrainConfig) -> float:
    """The discount of the reward normalisation: the algorithm's ``gamma`` (SB3 default 0.99)."""
    return float(tc.hyperparams.get("gamma", 0.99))


def make_model(
    cls: type[BaseAlgorithm],
    cfg: ExperimentConfig,
    tc: TrainConfig,
    venv: VecEnv,
    seed: int,
    run_dir: Path,
    state: dict[str, Any] | None,
) -> BaseAlgorithm:
    action_dim = int(venv.action_space.shape[0]) if venv.action_space.shape else None
    hyper = build_hyperparams(tc.algorithm, tc.hyperparams, action_dim)
    torch = require("torch")
    torch.set_num_threads(1)  # the envs need the other core(s)
    if state is None or not state.get("model"):
        return cls(
            tc.policy, venv, policy_kwargs=dict(tc.policy_kwargs) or None, seed=seed,
            tensorboard_log=str(run_dir / "tensorboard"), verbose=0, device="cpu", **hyper,
        )
    ckpt_dir = run_dir / "checkpoints"
    model = cls.load(
        ckpt_dir / state["model"], env=venv, device="cpu",
        tensorboard_log=str(run_dir / "tensorboard"),
    )
    if state.get("replay_buffer") and hasattr(model, "load_replay_buffer"):
        model.load_replay_buffer(ckpt_dir / state["replay_buffer"])
    return model


def eval_runner(
    cfg: ExperimentConfig, tc: TrainConfig, seed: int, stop: StopRequested
) -> Episodes:
    """The episodes that pick ``best_model.zip``, run in this process (on SUMO, or on the
    numpy rings with ``train.eval_backend: numpy``).

    Evaluation-mode rewards (Flow's ``env.evaluate``: the mean speed for the ring envs) and
    the same ``eval_episodes`` reset seeds at every evaluation, so scores are comparable.
    """
    seeds = [seed + 10_000 + i for i in range(tc.eval_episodes)]
    eval_cfg = replace(cfg, env=replace(cfg.env, evaluate=True))
    runner = NumpyEpisodeRunner if tc.eval_backend == "numpy" else EpisodeRunner
    return runner(eval_cfg, seeds, stop, tc.best_by)


def close_all(*envs: VecEnv | Episodes | None) -> None:
    for env in envs:
        if env is None:
            continue
        try:
            env.close()
        except (EOFError, BrokenPipeError, ConnectionResetError, OSError) as err:
            log.debug("env already gone at close: %s", err)  # workers died with Ctrl-C
