"""``flowrun baseline`` (and the shared options of commands that run simulations)."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeRemainingColumn

from flowrun.cli.common import (
    DEFAULT_OUT,
    AnyConfigArg,
    ConfigArg,
    NoRecordOpt,
    OutOpt,
    SeedOpt,
    SetOpt,
    StepsOpt,
    guarded,
    interrupt_between_steps,
    interrupted_exit,
    interruption_of,
    load_located,
    overrides_with_seed,
    sigterm_as_interrupt,
)
from flowrun.cli.feedback import Feedback
from flowrun.cli.tables import metrics_table, signals_table
from flowrun.errors import ConfigError, FlowrunError

if TYPE_CHECKING:
    from flowrun.config.model import ExperimentConfig
    from flowrun.experiment.baseline import BaselineResult

__all__ = [  # the shared options, re-exported for the commands that import them from here
    "AnyConfigArg",
    "ConfigArg",
    "OutOpt",
    "SeedOpt",
    "SetOpt",
    "baseline",
    "console",
    "interrupt_between_steps",
    "metrics_table",
    "overrides_with_seed",
    "register",
    "signals_table",
    "sigterm_as_interrupt",
]

console = Console()

#: Steps between progress-bar updates.
PROGRESS_EVERY = 100


@guarded
def baseline(
    config: AnyConfigArg,
    runs: Annotated[int, typer.Option("--runs", metavar="N",
    help="Number of runs.")] = 1,
    steps: StepsOpt = None,
    seed: SeedOpt = None,
    set_: SetOpt = None,
    out: OutOpt = DEFAULT_OUT,
    no_record: NoRecordOpt = False,
    record_every: Annotated[int, typer.Option(
        "--record-every",
        metavar="N",
        help="Log every N-th step.")] = 1,
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
    from flowrun.experiment.baseline import resolve_steps

    cfg = checked_baseline_config(config, overrides_with_seed(set_, seed))
    total = resolve_steps(cfg, steps)
    feedback = Feedback(console)
    what = f"{cfg.name}: {runs} run(s) x {steps_text(total, cfg.env.warmup_steps)}"
    feedback.phase(f"{what}; building the network and starting SUMO")
    options = dict(runs=runs, steps=steps, out=out, record=not no_record,
                   record_every=record_every, scene=scene, render=render, argv=sys.argv,
                   folder=folder)  # fmt: skip
    result = _run_with_progress(feedback, cfg, runs, total, options)
    _show_result(result, what)
    feedback.close(f"run folder: {result.run_dir}")


def checked_baseline_config(
    config: Path, overrides: list[str], command: str = "flowrun baseline"
) -> ExperimentConfig:
    """The config ``flowrun baseline`` runs, after the checks it makes before it starts (also
    ``flowrun sweep``'s, before any point): the env class and its params, and the SUMO backend.

    ``command`` names the refusing command in the message.

    Raises:
        ConfigError: at the ``file:line`` of the key (or its ``--set``).
    """
    from flowrun.fastring.plan import refuse_numpy_backend
    from flowrun.preflight.checks import preflight

    cfg, where = load_located(config, overrides)
    preflight(replace(cfg, train=None), where)  # env class and its params, at file:line
    try:
        refuse_numpy_backend(cfg, command)
    except ConfigError as err:
        raise where.error(err.message, ("sim", "backend")) from None
    return cfg


def _run_with_progress(
    feedback: Feedback, cfg: ExperimentConfig, runs: int, total: int, options: dict[str, Any]
) -> BaselineResult:
    """``run_baseline`` with a progress display; Ctrl-C/SIGTERM exit 130/143."""
    from flowrun.experiment.baseline import run_baseline

    columns = (
        TextColumn("run {task.fields[run]}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
    )
    with (
        feedback.progress(
            columns, lambda f: f"run {f['run']} of {runs}", total=total * runs, run=0
        ) as update,
        interrupt_between_steps() as check_stop,
    ):

        def progress(run: int, step: int) -> None:
            # The bar redraws ~10 times a second anyway; an update costs microseconds,
            # a noticeable share of one Sugiyama step.
            if step % PROGRESS_EVERY == 0 or step == total:
                update(completed=run * total + step, run=run)
            check_stop()

        try:
            return run_baseline(cfg, progress=progress, **options)
        except KeyboardInterrupt as err:
            raise interrupted_exit(
                err, "logs finished; status.json and metrics.json say so"
            ) from None
        except FlowrunError as err:
            # A Ctrl-C to the process group also stops a tool running then (netconvert):
            # its failure is the interruption.
            stopped = interruption_of(check_stop)
            if stopped is None:
                raise
            raise interrupted_exit(stopped, "status.json and metrics.json say so") from err


def _show_result(result: BaselineResult, title: str) -> None:
    """The runs' table (the signals' too on a network with traffic lights), the animation."""
    outflows = [] if result.signals else result.outflows
    console.print(metrics_table(title, result.metrics, outflows))
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


def steps_text(steps: int, warmup: int) -> str:
    """``3000 steps`` or ``300 steps after 750 warm-up steps``: what --steps and the horizon
    count (env steps), the warm-up apart."""
    return f"{steps} steps" + (f" after {warmup} warm-up steps" if warmup else "")


def register(app: typer.Typer) -> None:
    """Add the simulation commands (and ``convert``, Flow configs to YAML) to the app."""
    from flowrun.cli import commands_convert

    app.command("baseline")(baseline)
    commands_convert.register(app)
