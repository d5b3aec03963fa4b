"""``flowrun baseline``: run a config's environment N times with no learning, log and measure."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from contextlib import suppress
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from flowrun.config.dump import dump_config
from flowrun.config.model import ExperimentConfig
from flowrun.envs.base import Env
from flowrun.envs.factory import env_class, make_env
from flowrun.envs.frames import network_metadata
from flowrun.envs.render import kernel_road, snapshot, vehicle_lengths
from flowrun.errors import ConfigError
from flowrun.experiment.metrics import RunMetrics
from flowrun.experiment.runner import Experiment, FrameSink
from flowrun.experiment.signal_baselines import SignalMetrics, SignalRun
from flowrun.fastring.plan import refuse_numpy_backend
from flowrun.recording.scene import SceneEncoder
from flowrun.recording.writer import McapRecorder
from flowrun.render import Animation, Road, Snapshot, draw_run, write_animation
from flowrun.rundir.folders import (
    COMPLETE,
    FAILED,
    INTERRUPTED,
    RUNNING,
    check_out_dir,
    log_metadata,
    start_run,
    tracked_run,
    write_json,
)

log = logging.getLogger(__name__)

GIF_EVERY = 10  # simulation steps between two GIF frames
#: Outflow is counted over the last this many seconds of a run (Flow's ``outflows``), s.
OUTFLOW_WINDOW = 500


@dataclass
class BaselineResult:
    """What a baseline produced.

    Attributes:
        run_dir: the run folder.
        metrics: one entry per completed (or interrupted) run.
        logs: MCAP files written.
        status: ``complete`` or ``interrupted``.
        signals: on a network with traffic lights, each run's signal metrics (delay, travel
            time, throughput, queue, cars waiting at the end); empty otherwise.
        signal_controller: ``traffic_lights.controller`` (``None``: the network's programs
            or the environment's actions).
        animation: with ``render``: run 0's ``render.gif`` (and ``render.mp4`` where ffmpeg
            is installed, else a note why not).
        outflows: each run's outflow over its last :data:`OUTFLOW_WINDOW` s, veh/h (Flow's
            ``outflows``; ``metrics.json`` writes it as each run's ``outflow``).
    """

    run_dir: Path
    metrics: list[RunMetrics]
    logs: list[Path]
    status: str = "complete"
    signals: list[SignalMetrics] = field(default_factory=list)
    signal_controller: str | None = None
    animation: Animation | None = None
    outflows: list[float] = field(default_factory=list)


def resolve_steps(cfg: ExperimentConfig, steps: int | None) -> int:
    """Steps per run: ``--steps`` or the config's horizon (a whole number of steps, >= 1)."""
    if steps is not None:
        if steps < 1:
            raise ConfigError(f"--steps must be >= 1, got {steps}")
        return steps
    horizon = cfg.env.horizon
    if math.isinf(horizon):
        raise ConfigError(
            "env.horizon is infinite, so a run would never end; set env.horizon in the "
            "config or pass --steps N",
            path="env.horizon",
        )
    if math.isnan(horizon) or horizon < 1 or horizon != int(horizon):
        raise ConfigError(
            f"env.horizon is the number of steps of a run: a whole number >= 1, got {horizon!r}",
            path="env.horizon",
        )
    return int(horizon)


def open_run_log(
    path: Path,
    env: Env,
    cfg: ExperimentConfig,
    seed: int,
    run: int,
    record_every: int = 1,
    extra: dict[str, str] | None = None,
    scene: bool = False,
) -> McapRecorder:
    """The MCAP log of one run: metadata (with the network's main road and edge starts), the
    config and the network as attachments.

    Call after ``env.reset`` (the network file of the episode exists then).
    """
    attachments = {"config.yaml": dump_config(cfg).encode()}
    if env.k.net_file is not None:
        attachments["network.net.xml"] = env.k.net_file.read_bytes()
    meta = {
        **log_metadata(cfg, seed, run, record_every),
        **network_metadata(env.k),
        **(extra or {}),
    }
    encoder = SceneEncoder(kernel_road(env.k), vehicle_lengths(env.k)) if scene else None
    return McapRecorder(
        path, metadata=meta, attachments=attachments, record_every=record_every, scene=encoder
    )


def run_baseline(
    cfg: ExperimentConfig,
    *,
    runs: int = 1,
    steps: int | None = None,
    out: Path = Path("runs"),
    record: bool = True,
    record_every: int = 1,
    render: bool = False,
    scene: bool = False,
    argv: list[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
    folder: Path | None = None,
) -> BaselineResult:
    """Run the config's environment ``runs`` times and write the run folder.

    The seed is ``cfg.sim.seed`` (0 when unset); run ``i`` resets with seed ``seed + i``.
    The folder's ``status.json`` says ``running`` from the start and how the run ended at
    the end (see :mod:`flowrun.rundir.folders`); ``metrics.json`` is rewritten after
    every run, so even a killed run leaves the runs it finished. Interrupted by
    Ctrl-C/SIGTERM, the current log is finished, ``metrics.json`` and ``status.json`` say
    ``interrupted``, and the ``KeyboardInterrupt`` propagates.

    ``folder`` replaces ``out/<name>/<timestamp>-<seed>`` by that folder (``folder-1``, ...
    if it exists), as a sweep names its points.

    Raises:
        ConfigError: bad ``runs``/``steps``/``record_every``, or a config that cannot run.
        FlowrunError: the run folder cannot be created or written (disk full, read-only), or
            the simulation failed; a folder holding nothing but bookkeeping is removed.
    """
    if runs < 1:
        raise ConfigError(f"--runs must be >= 1, got {runs}")
    if record_every < 1:
        raise ConfigError(f"--record-every must be >= 1, got {record_every}")
    n_steps = resolve_steps(cfg, steps)
    seed = int(cfg.sim.seed or 0)
    # ``--steps`` is the episode length: the horizon follows it (and the saved config says so).
    cfg = replace(cfg, sim=replace(cfg.sim, seed=seed), env=replace(cfg.env, horizon=n_steps))
    env_class(cfg)  # a wrong env class or missing additional_params: fail before any file
    refuse_numpy_backend(cfg, "flowrun baseline")
    check_out_dir(folder.parent if folder is not None else out)
    run_dir = start_run(out, cfg, seed, argv, folder)
    with tracked_run(run_dir):
        return _run(cfg, run_dir, runs, n_steps, seed, record, record_every, render, progress,
                    scene)  # fmt: skip
    raise AssertionError("unreachable")  # pragma: no cover - tracked_run re-raises


def _run(
    cfg: ExperimentConfig,
    run_dir: Path,
    runs: int,
    n_steps: int,
    seed: int,
    record: bool,
    record_every: int,
    render: bool,
    progress: Callable[[int, int], None] | None,
    scene: bool = False,
) -> BaselineResult:
    env = _make_env(cfg, run_dir, seed, render)
    logs: list[Path] = []
    film = _Film() if render else None

    def sink(run: int) -> FrameSink:
        path = run_dir / f"run_{run}.mcap"
        logs.append(path)
        return open_run_log(path, env, cfg, seed + run, run, record_every, scene=scene)

    def on_step(run: int, step: int) -> None:
        if film is not None and run == 0 and step % GIF_EVERY == 0:
            film.take(env)
        if progress is not None:
            progress(run, step)

    has_lights = any(n.type == "traffic_light" for n in env.network.spec.nodes)
    signals = SignalRun(cfg.traffic_lights) if has_lights else None
    hooks = _Bookkeeping(signals, film)
    experiment = Experiment(
        env, sink_factory=sink if record else None, progress=on_step, hooks=hooks
    )
    head = {"config": cfg.name, "seed": seed, "runs_planned": runs, "steps_per_run": n_steps}

    def summary(status: str) -> dict[str, Any]:
        return _summary(status, head, experiment.metrics, hooks.outflows, signals, logs,
                        cfg.traffic_lights.controller)  # fmt: skip

    hooks.save = lambda: write_json(run_dir / "metrics.json", summary(RUNNING))
    write_json(run_dir / "metrics.json", summary(RUNNING))
    try:
        experiment.run(runs, n_steps, seed=seed)
    except BaseException as err:
        try:
            env.close()
        except Exception as again:  # SUMO may be gone already: report what stopped the run
            log.info("closing the environment failed too: %s", again)
        status = INTERRUPTED if isinstance(err, KeyboardInterrupt) else FAILED
        _write_final_metrics(run_dir / "metrics.json", summary(status))
        raise
    env.close()
    write_json(run_dir / "metrics.json", summary(COMPLETE))
    animation = film.write(run_dir / "render") if film is not None else None
    signal_runs = signals.results if signals is not None else []
    return BaselineResult(
        run_dir, experiment.metrics, logs, COMPLETE, signal_runs, cfg.traffic_lights.controller,
        animation, list(hooks.outflows),
    )  # fmt: skip


def _make_env(cfg: ExperimentConfig, run_dir: Path, seed: int, render: bool) -> Env:
    """The config's env, working in ``run_dir/sumo``; if making it fails (e.g. a user env's
    ``__init__``), ``metrics.json`` says so before the error propagates."""
    try:
        return make_env(cfg, render_mode="rgb_array" if render else None,
                        work_dir=run_dir / "sumo")  # fmt: skip
    except BaseException as err:
        status = INTERRUPTED if isinstance(err, KeyboardInterrupt) else FAILED
        with suppress(OSError):
            write_json(
                run_dir / "metrics.json",
                {"status": status, "partial": True, "config": cfg.name, "seed": seed,
                 "error": str(err).strip().splitlines()[0] if str(err).strip() else repr(err),
                 "runs": []},
            )  # fmt: skip
        raise


def _summary(
    status: str,
    head: dict[str, Any],
    metrics: list[RunMetrics],
    outflows: list[float],
    signals: SignalRun | None,
    logs: list[Path],
    signal_controller: str | None,
) -> dict[str, Any]:
    """``metrics.json``: the status, the run's facts (``head``: config, seed, runs planned,
    steps per run), one row per finished run (its metrics, outflow and signal measurements),
    the logs' names and, on a network with traffic lights (``signals``), their controller."""
    rows = [m.to_dict() for m in metrics]
    for row, outflow in zip(rows, outflows, strict=False):
        row["outflow"] = outflow
    for row, signal in zip(rows, signals.results if signals else [], strict=False):
        row.update(signal.to_dict())
    data: dict[str, Any] = {
        "status": status, "partial": status != COMPLETE, **head, "runs": rows,
        "logs": [p.name for p in logs],
    }  # fmt: skip
    if signals is not None:
        data["signal_controller"] = signal_controller
    return data


class _Film:
    """Run 0's pictures for ``--render``: the cars every ``GIF_EVERY`` steps from the start,
    drawn at the end on one speed scale (the run's fastest car) on the network's road."""

    def __init__(self) -> None:
        self.shots: list[Snapshot] = []
        self.road: Road | None = None
        self.lengths: dict[str, float] = {}
        self.resets = 0

    def take(self, env: Env) -> None:
        if self.road is None:
            self.road = kernel_road(env.k)
            self.lengths = vehicle_lengths(env.k)
        self.shots.append(snapshot(env.k))

    def on_reset(self, env: Env) -> None:
        self.resets += 1
        if self.resets == 1:
            self.take(env)  # the start (after the warm-up) is the first frame

    def write(self, stem: Path) -> Animation | None:
        if not self.shots:
            return None
        return write_animation(stem, draw_run(self.road, self.shots, self.lengths), fps=10.0)


def _write_final_metrics(path: Path, data: dict[str, Any]) -> None:
    """Write how a run that stopped ended; on a full disk, never leave a metrics.json that
    still says ``running``: remove it (which frees its room) and try again; if even that
    fails, there is no metrics.json and status.json tells (tracked_run reports the error)."""
    try:
        write_json(path, data)
    except OSError as again:
        log.info("metrics.json not written: %s; removing the stale one", again)
        with suppress(OSError):
            path.unlink()
            write_json(path, data)


class _Bookkeeping:
    """Hooks around every run: the signal controller (if any), each run's outflow, and
    ``metrics.json`` saved after every run (a killed run keeps the runs it finished)."""

    def __init__(self, signals: SignalRun | None, film: _Film | None = None) -> None:
        self.signals = signals
        self.film = film
        self.outflows: list[float] = []
        self.save: Callable[[], None] | None = None

    def on_reset(self, env: Env) -> None:
        if self.film is not None:
            self.film.on_reset(env)
        if self.signals is not None:
            self.signals.on_reset(env)

    def before_step(self, env: Env) -> None:
        if self.signals is not None:
            self.signals.before_step(env)

    def after_step(self, env: Env) -> None:
        if self.signals is not None:
            self.signals.after_step(env)

    def on_run_end(self, env: Env, run: int) -> None:
        if self.signals is not None:
            self.signals.on_run_end(env, run)
        rate = getattr(env.k.vehicle, "get_outflow_rate", None)
        self.outflows.append(float(rate(OUTFLOW_WINDOW)) if rate is not None else 0.0)
        if self.save is not None:
            try:
                self.save()
            except OSError as err:  # reported by the final write, or by what interrupted us
                log.info("metrics.json not updated: %s", err)
