"""What a replay is asked to do, checked before any work, and the steps it selects.

``flowrun replay`` parses its options into a :class:`ReplayRequest`, calls
:meth:`ReplayRequest.check` (every refusal before anything is read or written), then
:func:`select` (the logs opened, the selected steps and vehicles, their summaries). Both can be
used and tested without the command line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from flowrun.errors import RecordingError
from flowrun.recording import McapLog, open_log
from flowrun.replay.analysis import SpeedSeries, speed_series
from flowrun.replay.route import RouteLayout, layout_for, parse_route
from flowrun.replay.summary import ReplaySummary, summarize


@dataclass(frozen=True)
class ReplayRequest:
    """A replay's inputs and outputs (``None``: not asked for).

    Attributes:
        logs: one log, or two to compare.
        start: first simulation time to read, s.
        end: last simulation time to read, s.
        vehicles: ``--vehicles`` as given (``id,id,...``).
        route: ``--route`` as given (``edge,edge,...``).
        plot: what ``--plot`` draws (``time-space``, ``speed``, ...).
        out: the folder that receives the plots' folder.
        csv, foxglove, html: new files to write.
    """

    logs: list[Path]
    start: float | None = None
    end: float | None = None
    vehicles: str | None = None
    route: str | None = None
    plot: str | None = None
    out: Path | None = None
    csv: Path | None = None
    foxglove: Path | None = None
    html: Path | None = None

    def check(self) -> None:
        """Every refusal that needs no log read: counts, times, outputs that exist.

        Raises:
            RecordingError: what is wrong and how to fix it.
        """
        if not 1 <= len(self.logs) <= 2:
            raise RecordingError(f"replay takes one log or two to compare, got {len(self.logs)}")
        check_times(self.start, self.end)
        files = (self.csv, self.foxglove, self.html)
        if len(self.logs) == 2 and files != (None, None, None):
            raise RecordingError(
                "--csv, --foxglove and --html work on one log; drop the second log"
            )
        for path, option in zip(files, ("--csv", "--foxglove", "--html"), strict=True):
            check_new(path, option)
        out = self.out
        if self.plot is not None and out is not None and out.exists() and not out.is_dir():
            raise RecordingError(f"--out {out} is a file; give a folder for the plots")
        if self.plot is None and out is not None:
            raise RecordingError(
                "--out receives the plots of --plot; add --plot, or drop --out (--csv "
                "and --foxglove write exactly the file they name)"
            )
        self.chosen_vehicles()  # an empty --vehicles

    def chosen_vehicles(self) -> list[str] | None:
        """``--vehicles`` as a list of ids (``None``: all vehicles)."""
        if self.vehicles is None:
            return None
        ids = [v.strip() for v in self.vehicles.split(",") if v.strip()]
        if not ids:
            raise RecordingError("--vehicles needs comma-separated vehicle ids, e.g. idm_0,rl_0")
        return ids


@dataclass
class Selection:
    """The logs opened and what a request selects in each.

    Attributes:
        logs: the opened logs, in the request's order.
        layouts: each log's road to plot along (``None``: its own positions).
        series: each log's selected speeds.
        summaries: each log's summary of the selection.
        vehicles: the chosen vehicle ids (``None``: all).
        missing: chosen ids that no selected step holds.
    """

    logs: list[McapLog]
    layouts: list[RouteLayout | None]
    series: list[SpeedSeries]
    summaries: list[ReplaySummary]
    vehicles: list[str] | None = None
    missing: list[str] = field(default_factory=list)


def select(request: ReplayRequest) -> Selection:
    """Open the request's logs and select its window and vehicles.

    Raises:
        RecordingError: a log that cannot be read, a window without any logged step, chosen
            vehicles none of which is in the window.
    """
    chosen = request.chosen_vehicles()
    edges = parse_route(request.route) if request.route is not None else None
    opened = [open_log(p) for p in request.logs]
    layouts = [layout_for(lg, edges) for lg in opened]
    start, end = request.start, request.end
    series = [speed_series(lg, start_s=start, end_s=end, vehicles=chosen) for lg in opened]
    if (start is not None or end is not None) and not any(s.times.size for s in series):
        raise RecordingError(empty_window(opened, start, end))
    missing: list[str] = []
    if chosen is not None:
        seen = set().union(*(s.vehicle_types for s in series))
        if not seen:
            raise RecordingError(
                f"none of --vehicles {request.vehicles} appears in the selected steps"
            )
        missing = [v for v in chosen if v not in seen]
    summaries = [
        summarize(lg, start_s=start, end_s=end, vehicles=chosen, series=s)
        for lg, s in zip(opened, series, strict=True)
    ]
    return Selection(opened, layouts, series, summaries, chosen, missing)


def empty_window(logs: list[McapLog], start: float | None, end: float | None) -> str:
    """The message for a ``--from``/``--to`` window that holds no logged step."""
    spans = [lg.time_range for lg in logs]
    covers = " and ".join(f"{a:.1f}-{b:.1f} s" for a, b in filter(None, spans))
    window = " and ".join(
        f"{name} {value:g} s" for name, value in (("--from", start), ("--to", end))
        if value is not None
    )  # fmt: skip
    return f"no logged step within {window}; the log covers {covers or 'no time'}"


def check_new(path: Path | None, option: str) -> None:
    """Refuse an output that exists before any work is done (nothing is overwritten)."""
    if path is not None and path.is_dir():
        raise RecordingError(f"{option} {path} is a folder; give the new file's name in it")
    if path is not None and (path.exists() or path.is_symlink()):
        raise RecordingError(
            f"{option} {path} exists; choose a new path (flowrun never overwrites a file)"
        )


def check_times(start: float | None, end: float | None) -> None:
    """Refuse NaN times and a window that ends before it starts."""
    for option, value in (("--from", start), ("--to", end)):
        if value is not None and math.isnan(value):
            raise RecordingError(f"{option} is NaN; give a simulation time in seconds")
    if start is not None and end is not None and end < start:
        raise RecordingError(f"--to ({end}) is before --from ({start})")
