"""``flowrun baseline`` (and the shared options of commands that run simulations)."""

from __future__ import annotations

import signal
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from flowrun.cli.common import guarded

console = Console()

ConfigArg = Annotated[Path, typer.Argument(help="Experiment YAML file.", show_default=False)]
AnyConfigArg = Annotated[
    Path,
    typer.Argument(
        help="Experiment YAML file, or a Flow config module (.py defining flow_params).",
        show_default=False,
    ),
]
SetOpt = Annotated[
    list[str] | None,
    typer.Option("--set", help="Override a config value: a.b=value (YAML scalar). Repeatable."),
]
SeedOpt = Annotated[int | None, typer.Option("--seed", help="Seed (overrides sim.seed).")]
OutOpt = Annotated[Path, typer.Option("--out", help="Folder for run folders.")]


#: Steps between progress-bar updates.
PROGRESS_EVERY = 100


def overrides_with_seed(sets: list[str] | None, seed: int | None) -> list[str]:
    """``--set`` values plus ``--seed`` as the override ``sim.seed=S``."""
    items = list(sets or [])
    if seed is not None:
        items.append(f"sim.seed={seed}")
    return items


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Treat SIGTERM like Ctrl-C so ``finally`` blocks finish the logs."""

    def handler(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextmanager
def interrupt_between_steps() -> Iterator[Callable[[], None]]:
    """Ctrl-C/SIGTERM stop the run at the next step boundary (a second signal stops at once).

    Yields a ``check()`` to call between steps: it raises ``KeyboardInterrupt`` once a signal
    came. Raising from inside the signal handler could land in the middle of writing the log
    (the mcap writer compressing a chunk) and silently drop that chunk's steps.
    """
    requested = False

    def handler(signum: int, frame: Any) -> None:
        nonlocal requested
        if requested:
            raise KeyboardInterrupt
        requested = True

    def check() -> None:
        if requested:
            raise KeyboardInterrupt

    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield check
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


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
        table.add_row(str(i), f"{m.mean_delay:.1f} s", f"{m.mean_travel_time:.1f} s",
                      f"{m.throughput:.0f} veh/h", f"{m.mean_queue:.2f} veh",
                      str(m.waiting_at_end))  # fmt: skip
    return table


@guarded
def baseline(
    config: AnyConfigArg,
    runs: Annotated[int, typer.Option("--runs", help="Number of runs.")] = 1,
    steps: Annotated[
        int | None, typer.Option("--steps", help="Steps per run (default: env.horizon).")
    ] = None,
    seed: SeedOpt = None,
    set_: SetOpt = None,
    out: OutOpt = Path("runs"),
    no_record: Annotated[bool, typer.Option("--no-record", help="Do not write MCAP logs.")] = False,
    record_every: Annotated[int, typer.Option("--record-every", help="Log every N-th step.")] = 1,
    render: Annotated[
        bool, typer.Option("--render", help="Write run 0 as an animated GIF.")
    ] = False,
) -> None:
    """Run a non-RL experiment: N runs of the config's environment, a table, MCAP logs.

    CONFIG is a YAML file or a Flow config module (a .py file defining flow_params).
    """
    from flowrun.config.flow_module import load_any_config
    from flowrun.experiment.baseline import resolve_steps, run_baseline

    cfg = load_any_config(config, overrides_with_seed(set_, seed))
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
                    render=render,
                    argv=sys.argv,
                    progress=progress,
                )
            except KeyboardInterrupt:
                console.print("[yellow]interrupted[/]: logs finished; metrics.json says so")
                raise typer.Exit(code=130) from None
    console.print(metrics_table(f"{cfg.name}: {runs} run(s) x {total} steps", result.metrics))
    if result.signals:
        how = result.signal_controller or "the network's programs / the env's actions"
        console.print(signals_table(f"signal control: {how}", result.signals))
    console.print(f"run folder: {result.run_dir}")


def register(app: typer.Typer) -> None:
    """Add the simulation commands (and ``convert``, Flow configs to YAML) to the app."""
    from flowrun.cli import commands_convert

    app.command("baseline")(baseline)
    commands_convert.register(app)
