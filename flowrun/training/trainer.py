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
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from flowrun.config.model import ExperimentConfig, TrainConfig
from flowrun.envs.factory import env_class
from flowrun.errors import ConfigError, TrainingError
from flowrun.fastring.plan import check_numpy_backend
from flowrun.rundir.folders import exit_code_of, mark_done, mark_running, start_run
from flowrun.rundir.lock import FolderLock
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
        stopped_at_budget: training reached its ``deadline`` before ``total_timesteps`` (the
            run is ``complete``, with fewer steps).
    """

    run_dir: Path
    timesteps: int
    wall_clock: float
    status: str
    resumed_from: int = 0
    timing: TrainTiming | None = None
    stopped_at_budget: bool = False

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
    deadline: float | None = None,
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
        deadline: when learning stops at the latest (seconds since the epoch, a wall-time
            budget): at the next step boundary after it, the run ends as a ``complete`` one
            with fewer steps (final model, checkpoint), and ``metrics.json`` records
            ``stopped_at_budget: true`` and the deadline.

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
    cls = _check_before_work(cfg, tc)
    folder = _open_run(cfg, seed, out, resume_dir, argv)
    run = _TrainingRun(cfg, tc, seed, timing, should_stop or _never, folder, deadline)
    try:
        run.learn(cls, progress)
    except KeyboardInterrupt as err:
        run.interrupted(exit_code_of(err))
        raise
    except Exception as err:
        run.failed(err)  # raises unless asked to stop
    finally:
        run.close()
    wall = timing.total - timing.startup
    stopped = bool(run.budget.get("stopped_at_budget"))
    return TrainResult(run.run_dir, run.done, wall, run.status, run.resumed_from, timing, stopped)


def _check_before_work(cfg: ExperimentConfig, tc: TrainConfig) -> type[BaseAlgorithm]:
    """The algorithm class, after every check a config can fail before any work: the
    algorithm and its hyper-parameter names, the env class and its additional_params, and a
    numpy backend (of training or of the periodic evaluation) that cannot run the config."""
    cls = with_worker_rollouts(algorithm_class(tc.algorithm))
    build_hyperparams(tc.algorithm, tc.hyperparams)
    env_class(cfg)
    check_numpy_backend(cfg)
    if tc.eval_backend == "numpy" and tc.eval_freq > 0:
        numpy_eval_plan(cfg)
    return cls


class _RunFolder(NamedTuple):
    """A run folder being trained in, its resume state (``None``: a new run) and its lock."""

    run_dir: Path
    state: dict[str, Any] | None
    lock: FolderLock


def _open_run(
    cfg: ExperimentConfig, seed: int, out: Path, resume_dir: Path | None, argv: list[str] | None
) -> _RunFolder:
    """A new run folder under ``out``, or ``resume_dir`` marked running again (with its
    resume state); locked."""
    if resume_dir is None:
        run_dir = start_run(out, cfg, seed, argv)
        return _RunFolder(run_dir, None, RunLock(run_dir).acquire())
    state = resume_state(resume_dir)
    lock = RunLock(resume_dir).acquire()
    mark_running(resume_dir)
    note_resume(resume_dir, cfg, state, argv)
    keep_monitor_files(resume_dir, int(state["timesteps"]))
    return _RunFolder(resume_dir, state, lock)


class _TrainingRun:
    """One call of :func:`train`: its locked run folder, the parts it builds (env
    processes, model, evaluation episodes) and how it ended, which :meth:`close` writes to
    ``metrics.json`` and ``status.json`` whatever happened."""

    def __init__(self, cfg: ExperimentConfig, tc: TrainConfig, seed: int, timing: TrainTiming,
                 stop: StopRequested, folder: _RunFolder,
                 deadline: float | None = None) -> None:  # fmt: skip
        self.cfg, self.tc, self.seed, self.timing, self.stop = cfg, tc, seed, timing, stop
        self.deadline, self.at_deadline = deadline, _past(deadline)
        self.halt = _either(stop, self.at_deadline)  # a signal, or the budget's end
        self.budget = _budget_fields(deadline, False)
        self.run_dir, self.state, self.lock = folder
        self.resumed_from = int((self.state or {}).get("timesteps", 0))
        self.done = self.resumed_from
        self.status, self.error, self.exit_code = "failed", "", 1
        self.venv: VecEnv | None = None
        self.runner: Episodes | None = None
        self.model: BaseAlgorithm | None = None

    def learn(self, cls: type[BaseAlgorithm], progress: TrainProgress | None) -> None:
        """Build the envs and the model, learn up to ``total_timesteps`` (or a stop) and save."""
        cfg, tc, seed, run_dir, timing = self.cfg, self.tc, self.seed, self.run_dir, self.timing
        self._write_metrics("running")
        start_forkserver_shielded()
        self.venv = training_env(cfg, tc, seed, run_dir, self.state, timing)
        model = self.model = make_model(cls, cfg, tc, self.venv, seed, run_dir, self.state)
        callbacks = make_callbacks(
            tc.algorithm, run_dir / "checkpoints", tc.checkpoint_freq, progress,
            tc.total_timesteps, self.halt, timing,
        )
        callbacks.append(timing_callback(timing))
        if tc.eval_freq > 0:
            baseline = time.perf_counter()
            self.runner = eval_runner(cfg, tc, seed, self.stop)  # runs the all-human episodes
            timing.evaluation += time.perf_counter() - baseline
            callbacks.append(make_periodic_eval_callback(
                self.runner, run_dir, tc.eval_freq, BEST_MODEL, BEST_VECNORMALIZE, timing,
            ))
        extra = learn_kwargs(model, cfg, tc, seed, run_dir, self.halt)
        self.status = _learn(model, tc, callbacks, self.state, self.halt, extra)
        if self.status == "interrupted" and not self.stop() and self.at_deadline():
            self.status, self.budget = "complete", _budget_fields(self.deadline, True)
        self.done = int(model.num_timesteps)
        finish = time.perf_counter()
        _save_end(model, run_dir, tc, self.status)
        timing.finish = time.perf_counter() - finish
        self.exit_code = 0 if self.status == "complete" else _stop_code(self.stop)

    def interrupted(self, exit_code: int) -> None:
        """Stopped (Ctrl-C, or a child killed by the stop signal): save a checkpoint."""
        self.status, self.exit_code = "interrupted", exit_code
        _save_interrupted(self.model, self.run_dir, self.tc)

    def failed(self, err: Exception) -> None:
        """``err`` ended the training: re-raised (a dead env process as a
        :class:`TrainingError`), unless a stop was asked for."""
        if not self.stop():
            pipe = isinstance(err, EOFError | BrokenPipeError | ConnectionResetError)
            self.error = (f"an environment process stopped unexpectedly ({err!r})" if pipe
                          else f"{type(err).__name__}: {err}")  # fmt: skip
            if pipe:
                raise TrainingError(self.error) from err
            raise err
        # Asked to stop, and the signal also reached a child (an env process, netconvert
        # building the evaluation's ring): that is how the stop looks, not a failure.
        log.info("stopping: %r", err)
        self.interrupted(_stop_code(self.stop))

    def close(self) -> None:
        """Close the env processes and evaluation episodes, write how the run ended, unlock."""
        self.done = int(self.model.num_timesteps) if self.model is not None else self.done
        closing = time.perf_counter()
        close_all(self.venv, self.runner)
        self.timing.finish += time.perf_counter() - closing
        self.timing.total = time.perf_counter() - self.timing.started
        self._write_metrics(self.status)
        mark_done(self.run_dir, self.status, error=self.error or None, exit_code=self.exit_code)
        self.lock.release()

    def _write_metrics(self, status: str) -> None:
        _write_train_metrics(self.run_dir, self.cfg, self.tc, self.seed, status, self.done,
                             self.timing, self.state, self.budget)  # fmt: skip


def _never() -> bool:
    return False


def _past(deadline: float | None) -> StopRequested:
    """Whether the wall clock passed ``deadline`` (never, without one)."""
    if deadline is None:
        return _never
    return lambda: time.time() >= deadline


def _either(first: StopRequested, second: StopRequested) -> StopRequested:
    return lambda: first() or second()


def _budget_fields(deadline: float | None, stopped: bool) -> dict[str, Any]:
    """``metrics.json``'s record of a wall-time budget (nothing without one)."""
    if deadline is None:
        return {}
    when = datetime.fromtimestamp(deadline, UTC).isoformat(timespec="seconds")
    return {"budget_deadline": when, "stopped_at_budget": stopped}


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
    budget: dict[str, Any],
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
        **budget,
    )
