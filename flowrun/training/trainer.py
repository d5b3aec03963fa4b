"""``train``: a config's ``train:`` section -> a run folder with models, logs and an evaluation.

Run folder (``runs/<name>/<timestamp>-<seed>/``): ``config.yaml``, ``command.txt``,
``versions.json``, ``tensorboard/``, ``monitor/``, ``checkpoints/``, ``best_model.zip`` (when
evaluating during training), ``final_model.zip`` (+ ``vecnormalize.pkl``), ``metrics.json`` and
the final evaluation under ``eval/``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flowrun.config.loader import load_config
from flowrun.config.model import ExperimentConfig, TrainConfig
from flowrun.errors import ConfigError, TrainingError
from flowrun.experiment.rundir import create_run_dir, write_json
from flowrun.training.algorithms import algorithm_class, build_hyperparams
from flowrun.training.callbacks import (
    TrainProgress,
    make_callbacks,
    make_eval_callback,
    read_checkpoint_state,
    save_checkpoint,
)
from flowrun.training.deps import require
from flowrun.training.vecenv import make_vec_env, wrap_normalize

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.vec_env import VecEnv

log = logging.getLogger(__name__)

FINAL_MODEL = "final_model.zip"
BEST_MODEL = "best_model.zip"
VECNORMALIZE = "vecnormalize.pkl"


@dataclass
class TrainResult:
    """What a training run produced.

    Attributes:
        run_dir: the run folder.
        timesteps: environment steps done (over all envs, resumed ones included).
        wall_clock: seconds spent in this call's ``learn``.
        status: ``complete`` or ``interrupted``.
    """

    run_dir: Path
    timesteps: int
    wall_clock: float
    status: str


def train_section(cfg: ExperimentConfig) -> TrainConfig:
    """The config's ``train:`` section, or an error saying to add one."""
    if cfg.train is None:
        raise ConfigError(
            "this config has no train: section; add one (algorithm, total_timesteps, ...) "
            "as in configs/ring_wave.yaml",
            "train",
        )
    return cfg.train


def train_seed(cfg: ExperimentConfig) -> int:
    """The training seed: ``train.seed``, else ``sim.seed``, else 0."""
    tc = train_section(cfg)
    return int(tc.seed if tc.seed is not None else cfg.sim.seed or 0)


def train(
    cfg: ExperimentConfig,
    out: Path = Path("runs"),
    resume_dir: Path | None = None,
    progress: TrainProgress | None = None,
    argv: list[str] | None = None,
) -> TrainResult:
    """Train the config's policy with stable-baselines3 and write the run folder.

    Args:
        cfg: the experiment, with a ``train:`` section (ignored when resuming: the run
            folder's ``config.yaml`` is used).
        out: parent of new run folders.
        resume_dir: an earlier run folder to continue from its last checkpoint up to
            ``train.total_timesteps``.
        progress: called with ``(timesteps done, total, mean episode reward)``.
        argv: the command line saved in ``command.txt``.

    A ``KeyboardInterrupt`` (Ctrl-C, or SIGTERM turned into one by the CLI) saves a checkpoint,
    writes ``metrics.json`` with ``status: interrupted`` and propagates.
    """
    import time

    require("stable_baselines3")
    state: dict[str, Any] | None = None
    if resume_dir is not None:
        cfg, state = _resume_state(resume_dir)
        run_dir = resume_dir
    tc = train_section(cfg)
    seed = train_seed(cfg)
    cfg = replace(cfg, sim=replace(cfg.sim, seed=int(cfg.sim.seed or 0)))
    cls = algorithm_class(tc.algorithm)
    if resume_dir is None:
        run_dir = create_run_dir(out, cfg, seed, argv)
    ckpt_dir = run_dir / "checkpoints"
    venv = _training_env(cfg, tc, seed, run_dir, state)
    eval_env: VecEnv | None = None
    model: BaseAlgorithm | None = None
    start = time.monotonic()
    status = "interrupted"
    try:
        model = _model(cls, cfg, tc, venv, seed, run_dir, state)
        callbacks = make_callbacks(
            tc.algorithm, ckpt_dir, tc.checkpoint_freq, progress, tc.total_timesteps
        )
        if tc.eval_freq > 0:
            eval_env = make_vec_env(cfg, 1, seed + 10_000, subprocess=True)
            if tc.normalize:
                eval_env = wrap_normalize(eval_env, None, training=False)
            callbacks.append(
                make_eval_callback(
                    eval_env, run_dir, run_dir / "eval_log", tc.eval_freq, tc.n_envs,
                    tc.eval_episodes,
                )
            )
        remaining = tc.total_timesteps - int(model.num_timesteps)
        if remaining > 0:
            model.learn(
                remaining,
                callback=callbacks,
                tb_log_name="run",
                reset_num_timesteps=state is None,
            )
        status = "complete"
        model.save(run_dir / FINAL_MODEL)
        normalize = model.get_vec_normalize_env()
        if normalize is not None:
            normalize.save(str(run_dir / VECNORMALIZE))
        save_checkpoint(model, ckpt_dir, tc.algorithm)
    except KeyboardInterrupt:
        if model is not None:
            path = save_checkpoint(model, ckpt_dir, tc.algorithm)
            log.info("interrupted: checkpoint saved to %s", path)
        raise
    finally:
        wall = time.monotonic() - start
        done = int(model.num_timesteps) if model is not None else 0
        _close(venv, eval_env)
        _write_train_metrics(run_dir, cfg, tc, seed, status, done, wall, state)
    return TrainResult(run_dir, done, wall, status)


def _resume_state(run_dir: Path) -> tuple[ExperimentConfig, dict[str, Any]]:
    config = run_dir / "config.yaml"
    if not config.is_file():
        raise TrainingError(f"{run_dir} is not a run folder (no config.yaml); pass a train run")
    state = read_checkpoint_state(run_dir / "checkpoints")
    if state is None:
        raise TrainingError(
            f"{run_dir} has no checkpoint to resume from (no checkpoints/state.json); "
            "set train.checkpoint_freq or start a new run"
        )
    return load_config(config), state


def _training_env(
    cfg: ExperimentConfig, tc: TrainConfig, seed: int, run_dir: Path, state: dict[str, Any] | None
) -> VecEnv:
    monitor_dir = run_dir / "monitor"
    monitor_dir.mkdir(exist_ok=True)
    # Resumed runs reseed differently so they do not replay the first episodes.
    env_seed = seed if state is None else seed + int(state["timesteps"])
    venv = make_vec_env(cfg, tc.n_envs, env_seed, monitor_dir=None, subprocess=True)
    if tc.normalize:
        stats = None
        if state is not None and state.get("vecnormalize"):
            stats = run_dir / "checkpoints" / state["vecnormalize"]
        venv = wrap_normalize(venv, stats, training=True)
    return venv


def _model(
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
    if state is None:
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


def _close(*envs: VecEnv | None) -> None:
    for env in envs:
        if env is None:
            continue
        try:
            env.close()
        except (EOFError, BrokenPipeError, ConnectionResetError, OSError) as err:
            log.debug("env already gone at close: %s", err)  # workers died with Ctrl-C


def _write_train_metrics(
    run_dir: Path,
    cfg: ExperimentConfig,
    tc: TrainConfig,
    seed: int,
    status: str,
    done: int,
    wall: float,
    state: dict[str, Any] | None,
) -> None:
    write_json(
        run_dir / "metrics.json",
        {
            "status": status,
            "config": cfg.name,
            "seed": seed,
            "algorithm": tc.algorithm,
            "n_envs": tc.n_envs,
            "timesteps": done,
            "total_timesteps": tc.total_timesteps,
            "resumed_from": None if state is None else state["timesteps"],
            "wall_clock_s": round(wall, 3),
            "steps_per_s": round((done - (state or {}).get("timesteps", 0)) / wall, 1)
            if wall > 0 else None,
        },
    )
