"""``flowrun baseline`` (and the shared options of commands that run simulations)."""

from __future__ import annotations

import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from flowrun.cli.common import (
    DEFAULT_OUT,
    AnyConfigArg,
    ConfigArg,
    OutOpt,
    SeedOpt,
    SetOpt,
    guarded,
    interrupt_between_steps,
    interrupted_exit,
    load_located,
    overrides_with_seed,
    sigterm_as_interrupt,
)

__all__ = [  # the shared options, re-exported for the commands that import them from here
    "AnyConfigArg",
    "ConfigArg",
    "OutOpt",
    "SeedOpt",
    "SetOpt",
    "baseline",
    "console",
    "interrupt_between_steps",
    "overrides_with_seed",
    "register",
    "sigterm_as_interrupt",
]

console = Console()

#: Steps between progress-bar updates.
PROGRESS_EVERY = 100


def metrics_table(title: str, rows: list[Any]) -> Table:
    """The closing table: one row per run."""
    table = Table(title=title)
    for col in (
        "run",
        "mean speed",
        "last-half mean",
        "speed std",
        "min speed",
        "return",
        "collisions",
        "teleports",
    ):
        table.add_column(col, justify="right")
    for m in rows:
        table.add_row(
            str(m.run),
            f"{m.mean_speed:.3f} m/s",
            f"{m.last_half_mean_speed:.3f} m/s",
            f"{m.speed_std:.3f} m/s",
            f"{m.min_speed:.3f} m/s",
            f"{m.episode_return:.2f}",
            str(m.collisions),
            str(m.teleports),
        )
    return table


def signals_table(title: str, rows: list[Any]) -> Table:
    """The signal-control table: one row per run (:class:`SignalMetrics`)."""
    table = Table(title=title)
    for col in ("run", "mean delay", "mean travel time", "throughput", "mean queue",
                "waiting at end"):  # fmt: skip
        table.add_column(col, justify="right")
    for i, m in enumerate(rows):
        table.add_row(str(i), _value(m.mean_delay, ".1f", " s"),
                      _value(m.mean_travel_time, ".1f", " s"),
                      _value(m.throughput, ".0f", " veh/h"), _value(m.mean_queue, ".2f", " veh"),
                      str(m.waiting_at_end))  # fmt: skip
    return table


def _value(x: float | None, spec: str, unit: str) -> str:
    """A number with its unit, or "-" when it could not be measured (e.g. no car finished)."""
    if x is None or not math.isfinite(x):
        return "-"
    return f"{x:{spec}}{unit}"


@guarded
def baseline(
    config: AnyConfigArg,
    runs: Annotated[int, typer.Option("--runs", help="Number of runs.")] = 1,
    steps: Annotated[
        int | None, typer.Option("--steps", help="Steps per run (default: env.horizon).")
    ] = None,
    seed: SeedOpt = None,
    set_: SetOpt = None,
    out: OutOpt = DEFAULT_OUT,
    no_record: Annotated[bool, typer.Option("--no-record", help="Do not write MCAP logs.")] = False,
    record_every: Annotated[int, typer.Option("--record-every", help="Log every N-th step.")] = 1,
    scene: Annotated[
        bool,
        typer.Option(
            "--scene",
            help="Also log the road and the cars as a foxglove.SceneUpdate topic "
            "(/flowrun/scene) for Foxglove's 3D panel.",
        ),
    ] = False,
    render: Annotated[
        bool,
        typer.Option(
            "--render",
            help="Write run 0 as an animation of the traffic on its road "
            "(render.gif; render.mp4 too where ffmpeg is installed).",
        ),
    ] = False,
    folder: Annotated[
        Path | None, typer.Option("--folder", hidden=True, help="Exact run folder (sweeps).")
    ] = None,
) -> None:
    """Run a non-RL experiment: N runs of the config's environment, a table, MCAP logs.

    CONFIG is a YAML file or a Flow config module (a .py file defining flow_params).

    Run folder: OUT/<name>/<timestamp>-<seed>/ (status.json: running/complete/interrupted/failed).

    Ctrl-C or SIGTERM finishes the logs and exits 130 / 143.
    """
    from flowrun.config.preflight import preflight
    from flowrun.experiment.baseline import resolve_steps, run_baseline

    cfg, where = load_located(config, overrides_with_seed(set_, seed))
    preflight(replace(cfg, train=None), where)  # env class and its params, at file:line
    total = resolve_steps(cfg, steps)
    columns = (
        TextColumn("run {task.fields[run]}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
    )
    with Progress(
        *columns, console=console, transient=True, disable=not sys.stderr.isatty()
    ) as bar:
        task = bar.add_task("baseline", total=total * runs, run=0)

        with interrupt_between_steps() as check_stop:

            def progress(run: int, step: int) -> None:
                # The bar redraws ~10 times a second anyway; an update costs microseconds,
                # a noticeable share of one Sugiyama step.
                if step % PROGRESS_EVERY == 0 or step == total:
                    bar.update(task, completed=run * total + step, run=run)
                check_stop()

            try:
                result = run_baseline(
                    cfg,
                    runs=runs,
                    steps=steps,
                    out=out,
                    record=not no_record,
                    record_every=record_every,
                    scene=scene,
                    render=render,
                    argv=sys.argv,
                    progress=progress,
                    folder=folder,
                )
            except KeyboardInterrupt as err:
                raise interrupted_exit(
                    err, "logs finished; status.json and metrics.json say so"
                ) from None
    console.print(metrics_table(f"{cfg.name}: {runs} run(s) x {total} steps", result.metrics))
    if result.signals:
        how = result.signal_controller or "the network's programs / the env's actions"
        console.print(signals_table(f"signal control: {how}", result.signals))
    if result.animation is not None:
        console.print(
            f"wrote {result.animation.gif}"
            + (f" and {result.animation.mp4}" if result.animation.mp4 else "")
        )
        if result.animation.note:
            typer.secho(f"note: {result.animation.note}", err=True, fg=typer.colors.YELLOW)
    console.print(f"run folder: {result.run_dir}")


def register(app: typer.Typer) -> None:
    """Add the simulation commands (and ``convert``, Flow configs to YAML) to the app."""
    from flowrun.cli import commands_convert

    app.command("baseline")(baseline)
    commands_convert.register(app)
