"""``flowrun replay``: summary, comparison, plots, CSV export and repair of MCAP logs."""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Annotated, TypeVar

import typer
from rich.console import Console
from rich.table import Table

from flowrun.cli.common import (
    NO_SEED_OR_SET,
    guarded,
    interrupted_exit,
    out_option,
    sigterm_as_interrupt,
)
from flowrun.cli.replay_outputs import (
    PlotKind,
    draw_plots,
    export_foxglove,
    intersection_table,
    replay_dir,
)
from flowrun.cli.tables import NA
from flowrun.errors import RecordingError
from flowrun.recording import repair
from flowrun.replay import compare, summary_rows, to_csv
from flowrun.replay.html import write_html
from flowrun.replay.request import ReplayRequest, Selection, check_new, select
from flowrun.replay.signals import signal_series

T = TypeVar("T")


@contextmanager
def _warnings_to_stderr() -> Iterator[None]:
    """Show the recording layer's warnings (e.g. salvaged logs) as ``warning:`` lines."""

    class _Echo(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            typer.secho(f"warning: {record.getMessage()}", err=True, fg=typer.colors.YELLOW)

    logger = logging.getLogger("flowrun.recording")
    handler = _Echo(level=logging.WARNING)
    old_propagate = logger.propagate
    logger.addHandler(handler)
    logger.propagate = False
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.propagate = old_propagate


def _repair(logs: list[Path]) -> None:
    """``--repair IN OUT``: an interrupted repair leaves no file under OUT (exit 130/143)."""
    if len(logs) != 2:
        raise RecordingError(
            f"--repair takes an input and an output log (IN OUT), got {len(logs)} path(s)"
        )
    src, dst = logs
    check_new(dst, "--repair output")
    try:
        with sigterm_as_interrupt():
            report = repair(src, dst)
    except KeyboardInterrupt as err:
        raise interrupted_exit(
            err, f"repair stopped; nothing was written to {dst} and {src} is unchanged"
        ) from None
    state = "a damaged" if report.salvaged else "an intact"
    until = f" up to t={report.end_time:.1f} s" if report.end_time is not None else ""
    typer.echo(
        f"wrote {dst}: {report.frames} logged steps{until} from {state} log "
        f"({report.recovered_bytes} of {report.input_bytes} bytes usable)"
    )


def _interruptible(work: Callable[[], T], cleaned: str) -> T:
    """Run an export; Ctrl-C/SIGTERM stop it (its partial file removed) with exit 130/143."""
    try:
        with sigterm_as_interrupt():
            return work()
    except KeyboardInterrupt as err:
        raise interrupted_exit(err, f"export stopped; {cleaned}") from None


REPLAY_HELP = f"""Summarise a run's MCAP log (or compare two); plot it, export CSV, repair it.

Nothing is overwritten: --plot writes into a new folder each time (see --out), and --csv,
--foxglove, --html and --repair refuse a file that exists.

replay reads a log and {NO_SEED_OR_SET}: the log holds its seed and config.
"""


LogsArg = Annotated[
    list[Path],
    typer.Argument(help="One MCAP log, two to compare, or IN OUT with --repair.", metavar="LOG"),
]
FromOpt = Annotated[
    float | None,
    typer.Option("--from", metavar="SECONDS", help="First simulation time to read, in seconds."),
]
ToOpt = Annotated[
    float | None,
    typer.Option("--to", metavar="SECONDS", help="Last simulation time to read, in seconds."),
]
VehiclesOpt = Annotated[
    str | None,
    typer.Option("--vehicles", metavar="ID,ID,...", help="Only these vehicle ids: id,id,..."),
]
PlotOpt = Annotated[
    PlotKind | None,
    typer.Option(
        "--plot",
        metavar="time-space|speed|traffic|signals|all",
        help="Write PNG plots: time-space diagram, speeds, traffic (speed, density and outflow "
        "per minute), signals (queue per intersection approach with its signal shaded; logs "
        "of networks with traffic lights), or all.",
    ),
]
RouteOpt = Annotated[
    str | None,
    typer.Option(
        "--route",
        metavar="EDGE,EDGE,...",
        help="Edges of the road to plot along: a,b,c (default: the network's main road, e.g. "
        "inflow_highway,left,center on the merge; on a ring the ring).",
    ),
]
PlotsOutOpt = Annotated[
    Path | None,
    out_option(
        "a new folder of --plot's PNGs, OUT/<log>-<timestamp>/ (default OUT: <log folder>/replay)"
    ),
]
CsvOpt = Annotated[
    Path | None,
    typer.Option(
        "--csv", metavar="FILE", help="Export Flow emission-style CSV to exactly this new file."
    ),
]
RepairOpt = Annotated[
    bool,
    typer.Option(
        "--repair",
        help="Write a clean, indexed copy of what a damaged log still holds: --repair IN OUT "
        "(OUT must not exist; IN is only read).",
    ),
]
FoxgloveOpt = Annotated[
    Path | None,
    typer.Option(
        "--foxglove",
        metavar="FILE",
        help="Write the selected steps/vehicles to exactly this new MCAP file.",
    ),
]
HtmlOpt = Annotated[
    Path | None,
    typer.Option(
        "--html",
        metavar="FILE",
        help="Write a self-contained player page of the run (any browser, no server) to "
        "exactly this new file.",
    ),
]


@guarded
def replay(
    logs: LogsArg,
    start: FromOpt = None,
    end: ToOpt = None,
    vehicles: VehiclesOpt = None,
    plot: PlotOpt = None,
    route: RouteOpt = None,
    out: PlotsOutOpt = None,
    csv: CsvOpt = None,
    repair_: RepairOpt = False,
    foxglove: FoxgloveOpt = None,
    html: HtmlOpt = None,
) -> None:
    """Summarise, compare, plot, export or repair MCAP logs (help: REPLAY_HELP)."""
    plot_kind = plot.value if plot is not None else None
    request = ReplayRequest(logs, start, end, vehicles, route, plot_kind, out, csv, foxglove, html)
    try:
        with _warnings_to_stderr(), sigterm_as_interrupt():
            if repair_:
                _repair(logs)
            else:
                run_replay(request, Console())
    except KeyboardInterrupt as err:  # reading or drawing: nothing half written is left
        raise interrupted_exit(err, "replay stopped") from None


def run_replay(request: ReplayRequest, console: Console) -> None:
    """Check the request, print the summary (or comparison), then write what it asks for."""
    request.check()
    chosen = select(request)
    if chosen.missing:
        warn(f"vehicle id(s) not in the log: {', '.join(chosen.missing)}")
    console.print(summary_table(request.logs, chosen))
    for lg in chosen.logs:
        if lg.has_signals:
            console.print(intersection_table(lg, request.start, request.end))
    write_files(request, chosen)
    if request.plot is not None:
        write_plots(request, chosen)


def warn(text: str) -> None:
    """A ``warning:`` line on stderr."""
    typer.secho(f"warning: {text}", err=True, fg=typer.colors.YELLOW)


def summary_table(logs: list[Path], chosen: Selection) -> Table:
    """One log's summary, or two side by side with their difference. The return of an
    evaluation's all-human rollout is ``n/a``: without the policy no RL reward is summed (a
    benchmark's own baseline keeps it: its evaluate-mode return is the benchmark's metric)."""
    human = [lg.metadata.get("evaluation") == "baseline"
             and lg.metadata.get("baseline_kind") != "benchmark" for lg in chosen.logs]
    if len(chosen.summaries) == 1:
        table = Table(title=chosen.summaries[0].name, show_header=False)
        table.add_column("", style="bold")
        table.add_column("")
        for label, value in summary_rows(chosen.summaries[0]).items():
            table.add_row(label, NA if label == "return" and human[0] else value)
        return table
    table = Table(title="flowrun replay: comparison")
    table.add_column("", style="bold")
    table.add_column(f"A: {logs[0].name}")
    table.add_column(f"B: {logs[1].name}")
    table.add_column("B - A", justify="right")
    for label, (va, vb, delta) in compare(chosen.summaries[0], chosen.summaries[1]).items():
        if label == "return" and any(human):
            va, vb = (NA if h else v for h, v in zip(human, (va, vb), strict=True))
            delta = NA
        table.add_row(label, va, vb, delta)
    return table


def write_files(request: ReplayRequest, chosen: Selection) -> None:
    """``--csv``, ``--foxglove`` and ``--html``: each a new file, never half written."""
    log, start, end, ids = chosen.logs[0], request.start, request.end, chosen.vehicles
    if request.csv is not None:
        csv = request.csv
        rows = _interruptible(
            lambda: to_csv(log, csv, start_s=start, end_s=end, vehicles=ids, overwrite=False),
            f"nothing was written to {csv}",
        )
        typer.echo(f"wrote {csv} ({rows} rows)")
        if log.damage.data_lost:
            warn(f"{csv} lacks what the log lost: {log.damage.short()}")
    if request.foxglove is not None:
        fox = request.foxglove
        n = _interruptible(
            lambda: export_foxglove(log, fox, start, end, ids), f"nothing was written to {fox}"
        )
        typer.echo(f"wrote {fox} ({n} logged steps)")
    if request.html is not None:
        html = request.html
        page = _interruptible(
            lambda: write_html(log, html, start, end, ids), f"nothing was written to {html}"
        )
        typer.echo(f"wrote {html} ({page.bytes / 1e6:.1f} MB, {page.frames} steps)")
        for note in page.notes:
            typer.secho(f"note: {note}", err=True, fg=typer.colors.YELLOW)


def write_plots(request: ReplayRequest, chosen: Selection) -> None:
    """``--plot``: PNGs into a new folder; on Ctrl-C the finished ones are listed."""
    kind = PlotKind(request.plot or PlotKind.all)
    if kind is PlotKind.signals and not chosen.logs[0].has_signals:
        signal_series(chosen.logs[0])  # raises the readable "no traffic lights" error
    folder = replay_dir(request.out, request.logs)
    written: list[Path] = []
    try:
        with sigterm_as_interrupt():
            draw_plots(kind, chosen.logs, chosen.layouts, chosen.series, request.start,
                       request.end, chosen.vehicles, folder, written)  # fmt: skip
    except BaseException as err:
        for path in written:
            typer.echo(f"wrote {path}")
        with suppress(OSError):
            folder.rmdir()  # only if nothing was written
        if isinstance(err, KeyboardInterrupt):
            kept = f"{folder} holds the plots listed" if written else "no plot written"
            raise interrupted_exit(err, f"plotting stopped; {kept}") from None
        raise
    for path in written:
        typer.echo(f"wrote {path}")


def register(app: typer.Typer) -> None:
    """Add the ``replay`` command to ``app``."""
    app.command("replay", help=REPLAY_HELP)(replay)
