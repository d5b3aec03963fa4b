"""PNG plots of a logged run (matplotlib's object API with the Agg canvas: no display needed)."""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from flowrun.errors import RecordingError
from flowrun.recording import McapLog
from flowrun.replay.analysis import SpeedSeries, TimeSpace, speed_series, time_space_points
from flowrun.replay.summary import run_label

MAX_POINTS = 1_500_000
MAX_TRACES = 40
_COLORS = ("tab:blue", "tab:orange")


def _save(fig: Figure, out_png: str | os.PathLike[str]) -> Path:
    out = Path(out_png)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        FigureCanvasAgg(fig)
        fig.savefig(out, dpi=120)
    except OSError as err:
        raise RecordingError(f"cannot write plot {out}: {err}") from err
    return out


def plot_stride(log: McapLog) -> int:
    """Read every n-th step so a time-space plot stays around ``MAX_POINTS`` points."""
    frames = log.frame_count
    if not frames:
        return 1
    # vehicles per frame is not in the index: probe the first frame.
    first = next(log.vehicle_messages(), None)
    per_frame = len(first.ids) if first is not None else 1
    return max(1, int(np.ceil(frames * max(per_frame, 1) / MAX_POINTS)))


def plot_time_space(
    log: McapLog,
    out_png: str | os.PathLike[str],
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
    data: TimeSpace | None = None,
) -> Path:
    """Ring position vs time, points coloured by speed, RL vehicles highlighted."""
    ts = data or time_space_points(
        log, start_s=start_s, end_s=end_s, vehicles=vehicles, every=plot_stride(log)
    )
    fig = Figure(figsize=(10, 6), layout="constrained")
    ax = fig.add_subplot()
    size = max(0.5, min(6.0, 40_000 / max(ts.times.size, 1)))
    human = ~ts.is_rl
    sc = ax.scatter(
        ts.times[human],
        ts.positions[human],
        c=ts.speeds[human],
        s=size,
        cmap="RdYlGn",
        linewidths=0,
        rasterized=True,
        vmin=float(np.nanmin(ts.speeds)) if ts.speeds.size else 0.0,
        vmax=float(np.nanmax(ts.speeds)) if ts.speeds.size else 1.0,
    )
    if ts.is_rl.any():
        ax.scatter(
            ts.times[ts.is_rl],
            ts.positions[ts.is_rl],
            s=max(size, 2.0),
            color="black",
            marker="o",
            linewidths=0,
            rasterized=True,
            label="RL vehicle",
        )
        ax.legend(loc="upper right", markerscale=4)
    fig.colorbar(sc, ax=ax, label="Speed [m/s]")
    ax.set_xlabel("Time [s]")
    ax.set_ylabel("Position on ring [m]")
    ax.set_title(f"Time-space diagram - {run_label(log)}")
    return _save(fig, out_png)


def plot_speeds(
    logs: Sequence[McapLog],
    out_png: str | os.PathLike[str],
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
    series: Sequence[SpeedSeries] | None = None,
) -> Path:
    """Mean speed over time with min-max and +-std bands; one overlay per log (1 or 2)."""
    if series is None:
        chosen = None if vehicles is None else list(vehicles)
        series = [speed_series(lg, start_s=start_s, end_s=end_s, vehicles=chosen) for lg in logs]
    fig = Figure(figsize=(10, 5), layout="constrained")
    ax = fig.add_subplot()
    for i, (lg, s) in enumerate(zip(logs, series, strict=True)):
        color = _COLORS[i % len(_COLORS)]
        label = run_label(lg)
        ax.fill_between(s.times, s.min, s.max, color=color, alpha=0.12, linewidth=0)
        ax.fill_between(
            s.times, s.mean - s.std, s.mean + s.std, color=color, alpha=0.3, linewidth=0
        )
        ax.plot(s.times, s.mean, color=color, linewidth=1.2, label=f"mean speed, {label}")
    ax.set_xlabel("Time [s]")
    ax.set_ylabel("Speed [m/s]")
    names = " vs ".join(run_label(lg) for lg in logs)
    ax.set_title(
        f"Speed over time - {names}\n(dark band: mean +- std across vehicles; light band: min-max)",
        fontsize="medium",
    )
    ax.legend(loc="best", fontsize="small")
    ax.grid(alpha=0.3)
    return _save(fig, out_png)


def plot_vehicle_speeds(
    log: McapLog,
    out_png: str | os.PathLike[str],
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
    data: TimeSpace | None = None,
) -> Path:
    """Speed trace of each vehicle (at most ``MAX_TRACES``; RL vehicles always, in black)."""
    ts = data or time_space_points(
        log, start_s=start_s, end_s=end_s, vehicles=vehicles, every=plot_stride(log)
    )
    ids = list(dict.fromkeys(ts.ids.tolist()))
    rl = set(ts.ids[ts.is_rl].tolist())
    others = [v for v in ids if v not in rl]
    if len(others) + len(rl) > MAX_TRACES:
        pick = np.linspace(0, len(others) - 1, max(MAX_TRACES - len(rl), 1)).astype(int)
        others = [others[i] for i in sorted(set(pick.tolist()))]
    fig = Figure(figsize=(10, 5), layout="constrained")
    ax = fig.add_subplot()
    for vid in others:
        sel = ts.ids == vid
        ax.plot(ts.times[sel], ts.speeds[sel], linewidth=0.7, alpha=0.7)
    for vid in sorted(rl):
        sel = ts.ids == vid
        ax.plot(ts.times[sel], ts.speeds[sel], color="black", linewidth=1.6, label=f"{vid} (RL)")
    if rl:
        ax.legend(loc="best", fontsize="small")
    ax.set_xlabel("Time [s]")
    ax.set_ylabel("Speed [m/s]")
    shown = f"{len(others) + len(rl)} of {len(ids)} vehicles"
    ax.set_title(f"Vehicle speeds ({shown}) - {run_label(log)}")
    ax.grid(alpha=0.3)
    return _save(fig, out_png)
