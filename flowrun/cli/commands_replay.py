"""``flowrun replay``: summary, comparison, plots, CSV export and repair of MCAP logs."""

from __future__ import annotations

import logging
import math
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
from flowrun.errors import RecordingError
from flowrun.recording import open_log, repair
from flowrun.replay import (
    compare,
    layout_for,
    parse_route,
    speed_series,
    summarize,
    summary_rows,
    to_csv,
)
from flowrun.replay.html import write_html
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


def _parse_vehicles(text: str | None) -> list[str] | None:
    if text is None:
        return None
    ids = [v.strip() for v in text.split(",") if v.strip()]
    if not ids:
        raise RecordingError("--vehicles needs comma-separated vehicle ids, e.g. idm_0,rl_0")
    return ids


def _check_new(path: Path | None, option: str) -> None:
    """Refuse an output that exists before any work is done (nothing is overwritten)."""
    if path is not None and path.is_dir():
        raise RecordingError(f"{option} {path} is a folder; give the new file's name in it")
    if path is not None and (path.exists() or path.is_symlink()):
        raise RecordingError(
            f"{option} {path} exists; choose a new path (flowrun never overwrites a file)"
        )


def _check_times(start: float | None, end: float | None) -> None:
    for option, value in (("--from", start), ("--to", end)):
        if value is not None and math.isnan(value):
            raise RecordingError(f"{option} is NaN; give a simulation time in seconds")
    if start is not None and end is not None and end < start:
        raise RecordingError(f"--to ({end}) is before --from ({start})")


def _repair(logs: list[Path]) -> None:
    """``--repair IN OUT``: an interrupted repair leaves no file under OUT (exit 130/143)."""
    if len(logs) != 2:
        raise RecordingError(
            f"--repair takes an input and an output log (IN OUT), got {len(logs)} path(s)"
        )
    src, dst = logs
    _check_new(dst, "--repair output")
    try:
        with sigterm_as_interrupt():
            report = repair(src, dst)
    except KeyboardInterrupt as err:
        raise interrupted_exit(
            err, f"repair stopped; nothing was written to {dst} and {src} is unchanged"
        ) from None
    state = "damaged" if report.salvaged else "intact"
    until = f" up to t={report.end_time:.1f} s" if report.end_time is not None else ""
    typer.echo(
        f"wrote {dst}: {report.frames} logged steps{until} from a {state} log "
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


def register(app: typer.Typer) -> None:
    """Add the ``replay`` command to ``app``."""

    @app.command("replay", help=REPLAY_HELP)
    @guarded
    def replay(
        logs: Annotated[
            list[Path],
            typer.Argument(
                help="One MCAP log, two to compare, or IN OUT with --repair.", metavar="LOG"
            ),
        ],
        start: Annotated[
            float | None, typer.Option(
                "--from",
                metavar="SECONDS",
                help="First simulation time to read, in seconds.")
        ] = None,
        end: Annotated[
            float | None, typer.Option(
                "--to",
                metavar="SECONDS",
                help="Last simulation time to read, in seconds.")
        ] = None,
        vehicles: Annotated[
            str | None, typer.Option(
                "--vehicles",
                metavar="ID,ID,...",
                help="Only these vehicle ids: id,id,...")
        ] = None,
        plot: Annotated[
            PlotKind | None,
            typer.Option(
                "--plot",
                metavar="KIND",
                help="Write PNG plots: time-space diagram, speeds, traffic (speed, density "
                "and outflow per minute), signals (queue per intersection approach with its "
                "signal shaded; logs of networks with traffic lights), or all.",
            ),
        ] = None,
        route: Annotated[
            str | None,
            typer.Option(
                "--route",
                metavar="EDGE,EDGE,...",
                help="Edges of the road to plot along: a,b,c (default: the network's main "
                "road, e.g. inflow_highway,left,center on the merge; on a ring the ring).",
            ),
        ] = None,
        out: Annotated[
            Path | None,
            out_option(
                "a new folder of --plot's PNGs, OUT/<log>-<timestamp>/ (default OUT: "
                "<log folder>/replay)"
            ),
        ] = None,
        csv: Annotated[
            Path | None,
            typer.Option(
                "--csv",
                metavar="FILE",
                help="Export Flow emission-style CSV to exactly this new file."),
        ] = None,
        repair_: Annotated[
            bool,
            typer.Option(
                "--repair",
                help="Write a clean, indexed copy of what a damaged log still holds: "
                "--repair IN OUT (OUT must not exist; IN is only read).",
            ),
        ] = False,
        foxglove: Annotated[
            Path | None,
            typer.Option(
                "--foxglove",
                metavar="FILE",
                help="Write the selected steps/vehicles to exactly this new MCAP file.",
            ),
        ] = None,
        html: Annotated[
            Path | None,
            typer.Option(
                "--html",
                metavar="FILE",
                help="Write a self-contained player page of the run (any browser, no server) "
                "to exactly this new file.",
            ),
        ] = None,
    ) -> None:
        """Summarise, compare, plot, export or repair MCAP logs (help: REPLAY_HELP)."""
        console = Console()
        try:
            with _warnings_to_stderr(), sigterm_as_interrupt():
                if repair_:
                    _repair(logs)
                    return
                if not 1 <= len(logs) <= 2:
                    raise RecordingError(f"replay takes one log or two to compare, got {len(logs)}")
                _check_times(start, end)
                if len(logs) == 2 and (csv, foxglove, html) != (None, None, None):
                    raise RecordingError(
                        "--csv, --foxglove and --html work on one log; drop the second log"
                    )
                _check_new(csv, "--csv")
                _check_new(foxglove, "--foxglove")
                _check_new(html, "--html")
                if plot is not None and out is not None and out.exists() and not out.is_dir():
                    raise RecordingError(f"--out {out} is a file; give a folder for the plots")
                if plot is None and out is not None:
                    raise RecordingError(
                        "--out receives the plots of --plot; add --plot, or drop --out (--csv "
                        "and --foxglove write exactly the file they name)"
                    )
                chosen = _parse_vehicles(vehicles)
                edges = parse_route(route) if route is not None else None
                opened = [open_log(p) for p in logs]
                layouts = [layout_for(lg, edges) for lg in opened]
                series = [
                    speed_series(lg, start_s=start, end_s=end, vehicles=chosen) for lg in opened
                ]
                if (start is not None or end is not None) and not any(s.times.size for s in series):
                    spans = [lg.time_range for lg in opened]
                    covers = " and ".join(f"{a:.1f}-{b:.1f} s" for a, b in filter(None, spans))
                    window = " and ".join(
                        f"{name} {value:g} s"
                        for name, value in (("--from", start), ("--to", end))
                        if value is not None
                    )
                    raise RecordingError(
                        f"no logged step within {window}; the log covers {covers or 'no time'}"
                    )
                if chosen is not None:
                    seen = set().union(*(s.vehicle_types for s in series))
                    missing = [v for v in chosen if v not in seen]
                    if missing:
                        typer.secho(
                            f"warning: vehicle id(s) not in the log: {', '.join(missing)}",
                            err=True,
                            fg=typer.colors.YELLOW,
                        )
                    if not seen:
                        raise RecordingError(
                            f"none of --vehicles {vehicles} appears in the selected steps"
                        )
                summaries = [
                    summarize(lg, start_s=start, end_s=end, vehicles=chosen, series=s)
                    for lg, s in zip(opened, series, strict=True)
                ]
                if len(opened) == 1:
                    table = Table(title=summaries[0].name, show_header=False)
                    table.add_column("", style="bold")
                    table.add_column("")
                    for label, value in summary_rows(summaries[0]).items():
                        table.add_row(label, value)
                else:
                    table = Table(title="flowrun replay: comparison")
                    table.add_column("", style="bold")
                    table.add_column(f"A: {logs[0].name}")
                    table.add_column(f"B: {logs[1].name}")
                    table.add_column("B - A", justify="right")
                    for label, (va, vb, delta) in compare(summaries[0], summaries[1]).items():
                        table.add_row(label, va, vb, delta)
                console.print(table)
                for lg in opened:
                    if lg.has_signals:
                        console.print(intersection_table(lg, start, end))

                if csv is not None:
                    rows = _interruptible(
                        lambda: to_csv(
                            opened[0],
                            csv,
                            start_s=start,
                            end_s=end,
                            vehicles=chosen,
                            overwrite=False,
                        ),
                        f"nothing was written to {csv}",
                    )
                    typer.echo(f"wrote {csv} ({rows} rows)")
                    if opened[0].damage.data_lost:
                        typer.secho(
                            f"warning: {csv} lacks what the log lost: {opened[0].damage.short()}",
                            err=True,
                            fg=typer.colors.YELLOW,
                        )
                if foxglove is not None:
                    n = _interruptible(
                        lambda: export_foxglove(opened[0], foxglove, start, end, chosen),
                        f"nothing was written to {foxglove}",
                    )
                    typer.echo(f"wrote {foxglove} ({n} logged steps)")
                if html is not None:
                    page = _interruptible(
                        lambda: write_html(opened[0], html, start, end, chosen),
                        f"nothing was written to {html}",
                    )
                    typer.echo(f"wrote {html} ({page.bytes / 1e6:.1f} MB, {page.frames} steps)")
                    for note in page.notes:
                        typer.secho(f"note: {note}", err=True, fg=typer.colors.YELLOW)
                if plot is not None:
                    if plot is PlotKind.signals and not opened[0].has_signals:
                        signal_series(opened[0])  # raises the readable "no traffic lights" error
                    folder = replay_dir(out, logs)
                    written: list[Path] = []
                    try:
                        with sigterm_as_interrupt():
                            draw_plots(plot, opened, layouts, series, start, end, chosen, folder,
                                       written)  # fmt: skip
                    except BaseException as err:
                        for path in written:
                            typer.echo(f"wrote {path}")
                        with suppress(OSError):
                            folder.rmdir()  # only if nothing was written
                        if isinstance(err, KeyboardInterrupt):
                            kept = (
                                f"{folder} holds the plots listed" if written else "no plot written"
                            )
                            raise interrupted_exit(err, f"plotting stopped; {kept}") from None
                        raise
                    for path in written:
                        typer.echo(f"wrote {path}")
        except KeyboardInterrupt as err:  # reading or drawing: nothing half written is left
            raise interrupted_exit(err, "replay stopped") from None
