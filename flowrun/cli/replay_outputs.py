"""What ``flowrun replay`` writes: plots into a new folder, a Foxglove copy, the
intersection table. Split from :mod:`flowrun.cli.commands_replay` (the command itself)."""

from __future__ import annotations

from datetime import UTC, datetime
from enum import StrEnum
from pathlib import Path

from rich.table import Table

from flowrun.errors import FlowrunError, RecordingError
from flowrun.recording import McapLog, McapRecorder
from flowrun.recording.atomic import new_file
from flowrun.recording.scene import SceneEncoder
from flowrun.render import speed_top
from flowrun.replay import (
    RouteLayout,
    SpeedSeries,
    outflow,
    plot_speeds,
    plot_time_space,
    plot_traffic,
    plot_vehicle_speeds,
    time_space_points,
    traffic_series,
)
from flowrun.replay.html import log_road
from flowrun.replay.plots import plot_stride, shared_speed_range, shared_traffic_limits
from flowrun.replay.signal_plots import plot_signals
from flowrun.replay.signals import intersection_rows, signal_series
from flowrun.rundir.folders import unique_dir


class PlotKind(StrEnum):
    """What ``--plot`` draws."""

    time_space = "time-space"
    speed = "speed"
    traffic = "traffic"
    signals = "signals"
    all = "all"


def export_foxglove(
    log: McapLog, out: Path, start: float | None, end: float | None, vehicles: list[str] | None
) -> int:
    """Copy the selected steps/vehicles into a new log (opens in Foxglove like any flowrun log),
    with the ``/flowrun/scene`` topic for Foxglove's 3D panel."""
    stats = {s.step: s for s in log.stats(start, end)}
    signals = {s.step: s for s in log.signals(start, end)}
    top = speed_top(max((s.max_speed for s in stats.values() if s.num_vehicles), default=0.0))
    scene = SceneEncoder(log_road(log)[0], top=top)
    written = 0
    with (
        new_file(out, "--foxglove") as tmp,
        McapRecorder(tmp, metadata=log.metadata, attachments=log.attachments, scene=scene) as rec,
    ):
        for frame in log.frames(start, end, vehicles):
            if frame.step in stats:
                written += rec.write(frame, stats[frame.step], signals.get(frame.step))
    return written


def intersection_table(log: McapLog, start: float | None, end: float | None) -> Table:
    """Mean queue and delay per traffic light (definitions: :mod:`flowrun.replay.signals`)."""
    rows = intersection_rows(signal_series(log, start_s=start, end_s=end))
    table = Table(
        title=f"intersections - {log.path.name} (queue: cars < 0.1 m/s on the incoming edges; "
        "delay: time lost vs the speed limit there, per car)"
    )
    for name in rows[0] if rows else ("light",):
        table.add_column(name, justify="left" if name == "light" else "right")
    for row in rows:
        table.add_row(*row.values())
    return table


def replay_dir(out: Path | None, logs: list[Path]) -> Path:
    """A new folder for one replay's plots: ``OUT/<log>-<timestamp>/`` (two logs:
    ``<a>-vs-<b>-<timestamp>``), OUT defaulting to ``<first log's folder>/replay``; ``-1``,
    ``-2``, ... when taken, so no earlier plot is ever overwritten.

    Raises:
        RecordingError: ``out`` is a file.
        FlowrunError: the folder cannot be created (read-only, disk full).
    """
    parent = out if out is not None else logs[0].parent / "replay"
    if parent.exists() and not parent.is_dir():
        what = f"--out {parent}" if out is not None else f"{parent} (the default --out)"
        raise RecordingError(f"{what} is a file; give a folder for the plots (--out DIR)")
    stem = "-vs-".join(p.stem for p in logs)
    try:
        return unique_dir(parent / f"{stem}-{datetime.now(UTC).strftime('%Y%m%d-%H%M%S')}")
    except FlowrunError as err:
        if out is not None:
            raise
        raise RecordingError(f"{err}; give --out a folder you can write in") from None


def draw_plots(
    plot: PlotKind,
    opened: list[McapLog],
    layouts: list[RouteLayout | None],
    series: list[SpeedSeries],
    start: float | None,
    end: float | None,
    chosen: list[str] | None,
    folder: Path,
    written: list[Path],
) -> None:
    """Draw what ``--plot`` asks into ``folder``, adding each PNG to ``written`` once whole.
    Two runs compared share their colour scales and y-ranges."""
    suffixes = [""] if len(opened) == 1 else ["_A", "_B"]
    runs = list(zip(opened, layouts, suffixes, series, strict=True))
    if plot in (PlotKind.speed, PlotKind.all):
        written.append(plot_speeds(opened, folder / "speeds.png", series=series, vehicles=chosen))
    if plot in (PlotKind.time_space, PlotKind.all):
        datas = [
            time_space_points(lg, start_s=start, end_s=end, vehicles=chosen,
                              every=plot_stride(lg), route=layout)
            for lg, layout, _, _ in runs
        ]  # fmt: skip
        colours = shared_speed_range(datas)
        for (lg, layout, suffix, _), data in zip(runs, datas, strict=True):
            png = folder / f"time_space{suffix}.png"
            written.append(plot_time_space(lg, png, data=data, route=layout, speed_range=colours))
        if plot is PlotKind.all:  # every car, on the route shown or not
            cars = [
                data if layout is None else time_space_points(
                    lg, start_s=start, end_s=end, vehicles=chosen, every=plot_stride(lg))
                for (lg, layout, _, _), data in zip(runs, datas, strict=True)
            ]  # fmt: skip
            ylim = (0.0, shared_speed_range(cars)[1] * 1.05)
            for (lg, _, suffix, s), data in zip(runs, cars, strict=True):
                png = folder / f"vehicle_speeds{suffix}.png"
                total = len(s.vehicle_types)
                written.append(plot_vehicle_speeds(lg, png, data=data, total=total, ylim=ylim))
    if plot in (PlotKind.traffic, PlotKind.all):
        pairs = [
            (traffic_series(lg, layout, start_s=start, end_s=end),
             outflow(list(lg.stats(start, end))))
            for lg, layout, _, _ in runs
        ]  # fmt: skip
        limits = shared_traffic_limits(pairs) if len(pairs) > 1 else None
        for (lg, _, suffix, _), (traffic, flow) in zip(runs, pairs, strict=True):
            png = folder / f"traffic{suffix}.png"
            written.append(plot_traffic(lg, png, traffic, flow, ylims=limits))
    for lg, suffix in zip(opened, suffixes, strict=True):
        if plot in (PlotKind.signals, PlotKind.all) and lg.has_signals:
            lights = signal_series(lg, start_s=start, end_s=end)
            written.append(plot_signals(lg, folder / f"signals{suffix}.png", lights))
