"""``train``: a config's ``train:`` section -> a run folder with models, logs and an evaluation.

resume_config is re-exported from :mod:`flowrun.training.resume`.

Run folder (``runs/<name>/<timestamp>-<seed>/``): ``config.yaml``, ``command.txt``,
``versions.json``, ``tensorboard/``, ``monitor/``, ``checkpoints/``, ``best_model.zip`` (when
evaluating during training), ``final_model.zip`` (+ ``vecnormalize.pkl``), ``metrics.json`` and
the final evaluation under ``eval/``.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flowrun.config.model import ExperimentConfig, TrainConfig
from flowrun.envs.factory import env_class
from flowrun.errors import ConfigError, TrainingError
from flowrun.fastring.plan import check_numpy_backend
from flowrun.rundir.folders import exit_code_of, mark_done, mark_running, start_run
from flowrun.rundir.train_state import RunLock, StopRequest, write_status
from flowrun.training.algorithms import algorithm_class, build_hyperparams
from flowrun.training.callbacks import (
    StopRequested,
    TrainProgress,
    make_callbacks,
    save_checkpoint,
    save_model,
)
from flowrun.training.deps import require
from flowrun.training.numpy_eval import numpy_eval_plan
from flowrun.training.periodic_eval import Episodes, make_periodic_eval_callback
from flowrun.training.resume import (
    keep_monitor_files,
    note_resume,
    resume_state,
)
from flowrun.training.resume import (
    resume_config as resume_config,
)
from flowrun.training.run_parts import (
    close_all,
    eval_runner,
    learn_kwargs,
    make_model,
    start_forkserver_shielded,
    training_env,
)
from flowrun.training.timing import TrainTiming, timing_callback
from flowrun.training.worker_rollouts import with_worker_rollouts

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
        timing: where the time went.
    """

    run_dir: Path
    timesteps: int
    wall_clock: float
    status: str
    resumed_from: int = 0
    timing: TrainTiming | None = None

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
    should_stop: StopRequested | None = None,
) -> TrainResult:
    """Train the config's policy with stable-baselines3 and write the run folder.

    Args:
        cfg: the experiment, with a ``train:`` section. To resume, pass the run folder's
            config (:func:`resume_config`), possibly with a larger ``train.total_timesteps``.
        out: parent of new run folders.
        resume_dir: an earlier run folder to continue from its last checkpoint up to
            ``train.total_timesteps`` (it keeps being written to; nothing is overwritten).
        progress: called with ``(timesteps done, total, mean episode reward)``.
        argv: the command line saved in ``command.txt``.
        should_stop: polled at every step (and during evaluations); once true, training
            stops, saves a checkpoint and returns with ``status == "interrupted"``.

    A ``KeyboardInterrupt`` also saves a checkpoint, writes ``metrics.json`` with
    ``status: interrupted`` and propagates. While training, the folder is locked
    (:class:`RunLock`): a second resume of it is refused.

    Raises:
        TrainingError: no checkpoint to resume from, the folder is in use, an env process died.
    """
    timing = TrainTiming()
    require("stable_baselines3")
    tc = train_section(cfg)
    seed = train_seed(cfg)
    cfg = replace(cfg, sim=replace(cfg.sim, seed=int(cfg.sim.seed or 0)))
    cls = with_worker_rollouts(algorithm_class(tc.algorithm))
    build_hyperparams(tc.algorithm, tc.hyperparams)  # report a typo before any work
    env_class(cfg)  # a wrong env.class or missing additional_params, also before any work
    check_numpy_backend(cfg)  # sim.backend numpy: a config it cannot run, before any work
    if tc.eval_backend == "numpy" and tc.eval_freq > 0:
        numpy_eval_plan(cfg)  # likewise for the periodic evaluation's episodes
    state: dict[str, Any] | None = None
    if resume_dir is not None:
        run_dir = resume_dir
        state = resume_state(run_dir)
        lock = RunLock(run_dir).acquire()
        mark_running(run_dir)
        note_resume(run_dir, cfg, state, argv)
        keep_monitor_files(run_dir, int(state["timesteps"]))
    else:
        run_dir = start_run(out, cfg, seed, argv)
        lock = RunLock(run_dir).acquire()
    resumed_from = int((state or {}).get("timesteps", 0))
    stop = should_stop or _never
    status, done, error, exit_code = "failed", resumed_from, "", 1
    venv: VecEnv | None = None
    runner: Episodes | None = None
    model: BaseAlgorithm | None = None
    try:
        _write_train_metrics(run_dir, cfg, tc, seed, "running", done, timing, state)
        start_forkserver_shielded()
        venv = training_env(cfg, tc, seed, run_dir, state, timing)
        model = make_model(cls, cfg, tc, venv, seed, run_dir, state)
        callbacks = make_callbacks(
            tc.algorithm, run_dir / "checkpoints", tc.checkpoint_freq, progress,
            tc.total_timesteps, stop, timing,
        )
        callbacks.append(timing_callback(timing))
        if tc.eval_freq > 0:
            baseline = time.perf_counter()
            runner = eval_runner(cfg, tc, seed, stop)  # runs the all-human episodes
            timing.evaluation += time.perf_counter() - baseline
            callbacks.append(make_periodic_eval_callback(
                runner, run_dir, tc.eval_freq, BEST_MODEL, BEST_VECNORMALIZE, timing,
            ))
        extra = learn_kwargs(model, cfg, tc, seed, run_dir, stop)
        status = _learn(model, tc, callbacks, state, stop, extra)
        done = int(model.num_timesteps)
        finish = time.perf_counter()
        _save_end(model, run_dir, tc, status)
        timing.finish = time.perf_counter() - finish
        exit_code = 0 if status == "complete" else _stop_code(stop)
    except KeyboardInterrupt as err:
        status, exit_code = "interrupted", exit_code_of(err)
        _save_interrupted(model, run_dir, tc)
        raise
    except Exception as err:
        if not stop():
            pipe = isinstance(err, EOFError | BrokenPipeError | ConnectionResetError)
            error = (f"an environment process stopped unexpectedly ({err!r})" if pipe
                     else f"{type(err).__name__}: {err}")
            if pipe:
                raise TrainingError(error) from err
            raise
        # Asked to stop, and the signal also reached a child (an env process, netconvert
        # building the evaluation's ring): that is how the stop looks, not a failure.
        log.info("stopping: %r", err)
        status, exit_code = "interrupted", _stop_code(stop)
        _save_interrupted(model, run_dir, tc)
    finally:
        done = int(model.num_timesteps) if model is not None else done
        closing = time.perf_counter()
        close_all(venv, runner)
        timing.finish += time.perf_counter() - closing
        timing.total = time.perf_counter() - timing.started
        _write_train_metrics(run_dir, cfg, tc, seed, status, done, timing, state)
        mark_done(run_dir, status, error=error or None, exit_code=exit_code)
        lock.release()
    wall = timing.total - timing.startup
    return TrainResult(run_dir, done, wall, status, resumed_from, timing)


def _never() -> bool:
    return False


def _stop_code(stop: StopRequested) -> int:
    """130 (Ctrl-C) or 143 (SIGTERM), as the stop request knows."""
    return stop.exit_code if isinstance(stop, StopRequest) else 130


def _learn(
    model: BaseAlgorithm,
    tc: TrainConfig,
    callbacks: list[Any],
    state: dict[str, Any] | None,
    stop: StopRequested,
    extra: dict[str, Any],
) -> str:
    """Learn up to ``total_timesteps``; ``complete``, or ``interrupted`` when stopped."""
    remaining = tc.total_timesteps - int(model.num_timesteps)
    if remaining > 0 and not stop():
        model.learn(
            remaining, callback=callbacks, tb_log_name="run", reset_num_timesteps=state is None,
            **extra,
        )
    elif "async_eval" in extra:
        extra["async_eval"].close()
    return "interrupted" if stop() and model.num_timesteps < tc.total_timesteps else "complete"


def _save_end(model: BaseAlgorithm, run_dir: Path, tc: TrainConfig, status: str) -> None:
    """The checkpoint, and after a complete run the final model and its statistics."""
    if status == "complete":
        save_model(model, run_dir / FINAL_MODEL)
        normalize = model.get_vec_normalize_env()
        if normalize is not None:
            normalize.save(str(run_dir / VECNORMALIZE))
    path = save_checkpoint(model, run_dir / "checkpoints", tc.algorithm)
    log.info("%s: checkpoint saved to %s", status, path)


def _save_interrupted(model: BaseAlgorithm | None, run_dir: Path, tc: TrainConfig) -> None:
    if model is not None:
        _save_end(model, run_dir, tc, "interrupted")


def _write_train_metrics(
    run_dir: Path,
    cfg: ExperimentConfig,
    tc: TrainConfig,
    seed: int,
    status: str,
    done: int,
    timing: TrainTiming,
    state: dict[str, Any] | None,
) -> None:
    resumed = int((state or {}).get("timesteps", 0))
    learning = timing.total - timing.startup
    write_status(
        run_dir,
        status,
        config=cfg.name,
        seed=seed,
        algorithm=tc.algorithm,
        n_envs=tc.n_envs,
        timesteps=done,
        total_timesteps=tc.total_timesteps,
        resumed_from=None if state is None else resumed,
        wall_clock_s=round(timing.total, 3),
        steps_per_s=round((done - resumed) / learning, 1) if learning > 0 else None,
        timing=timing.to_dict(),
    )
