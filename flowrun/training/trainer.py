"""``train``: a config's ``train:`` section -> a run folder with models, logs and an evaluation.

Run folder (``runs/<name>/<timestamp>-<seed>/``): ``config.yaml``, ``command.txt``,
``versions.json``, ``tensorboard/``, ``monitor/``, ``checkpoints/``, ``best_model.zip`` (when
evaluating during training), ``final_model.zip`` (+ ``vecnormalize.pkl``), ``metrics.json`` and
the final evaluation under ``eval/``.
"""

from __future__ import annotations

import logging
import shlex
import sys
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flowrun.config.dump import dump_config
from flowrun.config.loader import load_config
from flowrun.config.model import ExperimentConfig, TrainConfig
from flowrun.envs.factory import env_class
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
BEST_VECNORMALIZE = "best_vecnormalize.pkl"


@dataclass
class TrainResult:
    """What a training run produced.

    Attributes:
        run_dir: the run folder.
        timesteps: environment steps done (over all envs, resumed ones included).
        wall_clock: seconds spent in this call's ``learn`` (evaluations during it included).
        status: ``complete`` or ``interrupted``.
        resumed_from: timesteps of the checkpoint this call started from (0 for a new run).
    """

    run_dir: Path
    timesteps: int
    wall_clock: float
    status: str
    resumed_from: int = 0

    @property
    def steps_per_second(self) -> float:
        """Environment steps per second of this call."""
        done = self.timesteps - self.resumed_from
        return done / self.wall_clock if self.wall_clock > 0 else 0.0


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
        cfg: the experiment, with a ``train:`` section. To resume, pass the run folder's
            config (:func:`resume_config`), possibly with a larger ``train.total_timesteps``.
        out: parent of new run folders.
        resume_dir: an earlier run folder to continue from its last checkpoint up to
            ``train.total_timesteps`` (it keeps being written to).
        progress: called with ``(timesteps done, total, mean episode reward)``.
        argv: the command line saved in ``command.txt``.

    A ``KeyboardInterrupt`` (Ctrl-C, or SIGTERM turned into one by the CLI) saves a checkpoint,
    writes ``metrics.json`` with ``status: interrupted`` and propagates.
    """
    import time

    require("stable_baselines3")
    tc = train_section(cfg)
    seed = train_seed(cfg)
    cfg = replace(cfg, sim=replace(cfg.sim, seed=int(cfg.sim.seed or 0)))
    cls = algorithm_class(tc.algorithm)
    build_hyperparams(tc.algorithm, tc.hyperparams)  # report a typo before any work
    env_class(cfg)  # a wrong env.class or missing additional_params, also before any work
    state: dict[str, Any] | None = None
    if resume_dir is not None:
        state = _resume_state(resume_dir)
        run_dir = resume_dir
        _note_resume(run_dir, cfg, state, argv)
    else:
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
            eval_env = _eval_env(cfg, tc, seed)
            callbacks.append(
                make_eval_callback(
                    eval_env, run_dir, run_dir / "eval_log", tc.eval_freq, tc.n_envs,
                    tc.eval_episodes, BEST_VECNORMALIZE,
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
    return TrainResult(run_dir, done, wall, status, int((state or {}).get("timesteps", 0)))


def resume_config(run_dir: Path, overrides: Sequence[str] = ()) -> ExperimentConfig:
    """A run folder's saved config with ``--set`` overrides (e.g. more ``total_timesteps``)."""
    config = run_dir / "config.yaml"
    if not config.is_file():
        raise TrainingError(f"{run_dir} is not a run folder (no config.yaml); pass a train run")
    return load_config(config, overrides)


def _resume_state(run_dir: Path) -> dict[str, Any]:
    state = read_checkpoint_state(run_dir / "checkpoints")
    if state is None:
        raise TrainingError(
            f"{run_dir} has no checkpoint to resume from (no checkpoints/state.json); "
            "set train.checkpoint_freq or start a new run"
        )
    return state


def _note_resume(
    run_dir: Path, cfg: ExperimentConfig, state: dict[str, Any], argv: list[str] | None
) -> None:
    """Append the command line; keep the earlier config if the resumed one differs."""
    command = argv if argv is not None else sys.argv
    with (run_dir / "command.txt").open("a") as f:
        f.write(shlex.join(command) + "\n")
    text = dump_config(cfg)
    current = run_dir / "config.yaml"
    if current.read_text() != text:
        current.rename(run_dir / f"config.before_{state['timesteps']}.yaml")
        current.write_text(text)


def _training_env(
    cfg: ExperimentConfig, tc: TrainConfig, seed: int, run_dir: Path, state: dict[str, Any] | None
) -> VecEnv:
    monitor_dir = run_dir / "monitor"
    monitor_dir.mkdir(exist_ok=True)
    # Resumed runs reseed differently so they do not replay the first episodes.
    env_seed = seed if state is None else seed + int(state["timesteps"])
    venv = make_vec_env(cfg, tc.n_envs, env_seed, monitor_dir=monitor_dir, subprocess=True)
    if tc.normalize:
        stats = None
        if state is not None and state.get("vecnormalize"):
            stats = run_dir / "checkpoints" / state["vecnormalize"]
        venv = wrap_normalize(venv, stats, training=True, gamma=_gamma(tc))
    return venv


def _eval_env(cfg: ExperimentConfig, tc: TrainConfig, seed: int) -> VecEnv:
    """The env ``EvalCallback`` scores models on (picking ``best_model.zip``).

    Evaluation-mode rewards (Flow's ``env.evaluate``: the mean speed for the ring envs), and
    the same ``eval_episodes`` reset seeds at every evaluation, so scores are comparable.
    SB3 resets once more after the last episode, hence one extra seed in the cycle.
    """
    eval_cfg = replace(cfg, env=replace(cfg.env, evaluate=True))
    seeds = tuple(seed + 10_000 + i for i in range(tc.eval_episodes + 1))
    env = make_vec_env(eval_cfg, 1, seed + 10_000, subprocess=True, cycle_seeds=seeds)
    if tc.normalize:
        env = wrap_normalize(env, None, training=False, gamma=_gamma(tc))
    return env


def _gamma(tc: TrainConfig) -> float:
    """The discount of the reward normalisation: the algorithm's ``gamma`` (SB3 default 0.99)."""
    return float(tc.hyperparams.get("gamma", 0.99))


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
