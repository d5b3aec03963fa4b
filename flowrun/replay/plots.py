"""PNG plots of a logged run (matplotlib's object API with the Agg canvas: no display needed)."""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np
import yaml
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from flowrun.errors import RecordingError
from flowrun.recording import McapLog
from flowrun.recording.writer import ROSTER_METADATA
from flowrun.replay.analysis import SpeedSeries, TimeSpace, speed_series, time_space_points
from flowrun.replay.route import RouteLayout
from flowrun.replay.summary import run_label
from flowrun.replay.traffic import Outflow, TrafficSeries

MAX_POINTS = 1_500_000
MAX_TRACES = 40
MAX_RL_TRACES = 10
MAX_RL_LABELS = 6
_COLORS = ("tab:blue", "tab:orange")


def _save(fig: Figure, out_png: str | os.PathLike[str]) -> Path:
    """Write ``fig`` as a PNG, whole or not at all: drawn into a hidden partial file that is
    renamed when complete, so a Ctrl-C or a full disk never leaves half an image."""
    out = Path(out_png)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.partial")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        FigureCanvasAgg(fig)
        fig.savefig(tmp, dpi=120, format="png")
        os.replace(tmp, out)
    except OSError as err:
        raise RecordingError(f"cannot write plot {out}: {err}") from err
    finally:
        tmp.unlink(missing_ok=True)
    return out


def warmup_end(log: McapLog) -> float | None:
    """Simulation time at which the run's warm-up ended, s (``None`` without a warm-up, or a
    log whose config does not say)."""
    text = log.metadata.get("config")
    if not text:
        return None
    try:
        cfg = yaml.safe_load(text)
        steps = int(cfg["env"]["warmup_steps"])
        dt = float(cfg["sim"]["step"])
    except (yaml.YAMLError, KeyError, TypeError, ValueError):
        return None
    return steps * dt if steps > 0 else None


def mark_warmup(ax: Axes, log: McapLog) -> None:
    """Shade and label the warm-up (steps before control starts) on a time axis."""
    end = warmup_end(log)
    if end is None:
        return
    ax.axvspan(0.0, end, color="grey", alpha=0.12, linewidth=0, zorder=0)
    ax.annotate("warm-up", (end / 2, 1.0), xycoords=("data", "axes fraction"),
                xytext=(0, -10), textcoords="offset points", ha="center",
                fontsize="x-small", color="dimgrey")  # fmt: skip


def vehicles_label(vehicles: Iterable[str] | None, most: int = 4) -> str:
    """How a plot names its selection: all vehicles, or the ``--vehicles`` ids."""
    if vehicles is None:
        return "all vehicles"
    ids = list(vehicles)
    shown = ", ".join(ids[:most]) + (f" +{len(ids) - most} more" if len(ids) > most else "")
    return f"vehicle{'s' if len(ids) > 1 else ''} {shown}"


def plot_stride(log: McapLog) -> int:
    """Read every n-th step so a time-space plot stays around ``MAX_POINTS`` points."""
    frames = log.frame_count
    if not frames:
        return 1
    # vehicles per frame is not in the index. With one roster all frames have the first
    # one's; where cars come and go (open networks) the stats topic has every step's count.
    fixed = log.all_metadata.get(ROSTER_METADATA, {}).get("rosters") == "1"
    counts = [] if fixed else [s.num_vehicles for s in log.stats()]
    if counts:
        total = sum(counts) * frames / len(counts)
    else:
        first = next(log.vehicle_messages(), None)
        total = frames * max(len(first.ids) if first is not None else 1, 1)
    return max(1, int(np.ceil(total / MAX_POINTS)))


def plot_time_space(
    log: McapLog,
    out_png: str | os.PathLike[str],
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
    data: TimeSpace | None = None,
    route: RouteLayout | None = None,
    speed_range: tuple[float, float] | None = None,
) -> Path:
    """Position vs time, points coloured by speed, RL vehicles highlighted.

    The position is along ``route`` (dotted lines where its edges start) when one is given,
    else the logged network position (the ring position on a ring). ``data``, when given,
    must have been read with the same ``route``. ``speed_range`` fixes the colour scale (two
    runs compared side by side share one); by default 0 to the fastest point.
    """
    ts = data or time_space_points(
        log,
        start_s=start_s,
        end_s=end_s,
        vehicles=vehicles,
        every=plot_stride(log),
        route=route,
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
        vmin=speed_range[0] if speed_range else 0.0,
        vmax=speed_range[1] if speed_range else _top(ts.speeds),
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
    _position_axis(ax, log, route)
    mark_warmup(ax, log)
    ax.set_title(f"Time-space diagram - {run_label(log)}")
    return _save(fig, out_png)


def _position_axis(ax: Axes, log: McapLog, route: RouteLayout | None) -> None:
    """Label the position axis: along ``route`` (dotted lines where its edges start), else
    the ring or network position."""
    if route is None:
        ring = log.metadata.get("network_closed", "true") == "true"
        ax.set_ylabel("Position on ring [m]" if ring else "Position in the network [m]")
        return
    ax.set_ylabel(f"Position along {route.label} [m]")
    ax.set_ylim(0.0, route.length)
    for edge, start in route.edge_starts():
        ax.axhline(start, color="grey", linewidth=0.6, linestyle=":")
        ax.annotate(
            edge, (0.0, start), xycoords=("axes fraction", "data"), xytext=(3, 2),
            textcoords="offset points", fontsize="x-small", color="dimgrey",
        )  # fmt: skip


def _top(speeds: np.ndarray) -> float:
    finite = speeds[np.isfinite(speeds)]
    return max(float(finite.max()), 1e-3) if finite.size else 1.0


def shared_speed_range(datas: Sequence[TimeSpace]) -> tuple[float, float]:
    """One colour scale for time-space diagrams compared side by side: 0 to the fastest."""
    tops = [_top(d.speeds) for d in datas if d.speeds.size]
    return 0.0, max(tops, default=1.0)


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
        low = np.maximum(s.mean - s.std, 0.0)  # a speed is never negative
        ax.fill_between(s.times, low, s.mean + s.std, color=color, alpha=0.3, linewidth=0)
        ax.plot(s.times, s.mean, color=color, linewidth=1.2, label=f"mean speed, {label}")
    ax.set_xlabel("Time [s]")
    ax.set_ylabel("Speed [m/s]")
    ax.set_ylim(bottom=0.0)
    mark_warmup(ax, logs[0])
    names = " vs ".join(run_label(lg) for lg in logs)
    ax.set_title(
        f"Speed of {vehicles_label(vehicles)} over time - {names}\n(dark band: mean +- std "
        "across them, not below 0; light band: min-max)",
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
    total: int | None = None,
    ylim: tuple[float, float] | None = None,
) -> Path:
    """Speed trace of each vehicle, at most ``MAX_TRACES`` picked evenly in order of
    appearance; RL vehicles in black (all of them up to ``MAX_RL_TRACES``, each named up to
    ``MAX_RL_LABELS``). ``total``: how many vehicles the log holds in the selection (the
    title's "of N"; default: those in ``data``); ``ylim``: a speed range shared with a run
    compared side by side."""
    ts = data or time_space_points(
        log, start_s=start_s, end_s=end_s, vehicles=vehicles, every=plot_stride(log)
    )
    ids = list(dict.fromkeys(ts.ids.tolist()))
    rl_set = set(ts.ids[ts.is_rl].tolist())
    rl = _evenly([v for v in ids if v in rl_set], MAX_RL_TRACES)
    others = _evenly([v for v in ids if v not in rl_set], max(MAX_TRACES - len(rl), 1))
    fig = Figure(figsize=(10, 5), layout="constrained")
    ax = fig.add_subplot()
    for vid in others:
        sel = ts.ids == vid
        ax.plot(ts.times[sel], ts.speeds[sel], linewidth=0.7, alpha=0.7)
    named = len(rl) <= MAX_RL_LABELS
    for k, vid in enumerate(rl):
        sel = ts.ids == vid
        label = f"{vid} (RL)" if named else ("RL vehicles" if k == 0 else None)
        ax.plot(ts.times[sel], ts.speeds[sel], color="black", linewidth=1.6, label=label)
    if rl:
        ax.legend(loc="best", fontsize="small")
    ax.set_xlabel("Time [s]")
    ax.set_ylabel("Speed [m/s]")
    ax.set_ylim(*(ylim or (0.0, _top(ts.speeds) * 1.05)))
    mark_warmup(ax, log)
    shown = f"{len(others) + len(rl)} of {total if total is not None else len(ids)} vehicles"
    ax.set_title(f"Vehicle speeds ({shown}) - {run_label(log)}")
    ax.grid(alpha=0.3)
    return _save(fig, out_png)


def _evenly(ids: list[str], most: int) -> list[str]:
    """At most ``most`` of ``ids``, picked evenly from first to last."""
    if len(ids) <= most:
        return ids
    pick = np.linspace(0, len(ids) - 1, most).astype(int)
    return [ids[i] for i in sorted(set(pick.tolist()))]


def plot_traffic(
    log: McapLog,
    out_png: str | os.PathLike[str],
    series: TrafficSeries,
    flow: Outflow,
    ylims: dict[str, tuple[float, float]] | None = None,
) -> Path:
    """Speed and density on the road and outflow per bin (veh/h), over time.

    On a closed network (a ring) no car leaves and the number of cars is fixed, so there the
    density and outflow panels are replaced by one line saying so: a flat line and an all-zero
    bar chart would look like findings. ``ylims`` (``speed``, ``density``, ``outflow``) share
    the y-ranges with a run compared side by side.
    """
    closed = log.metadata.get("network_closed") == "true"
    fig = Figure(figsize=(10, 4.5 if closed else 8), layout="constrained")
    if closed:
        speed_ax = fig.subplots(1, 1)
        axes = [speed_ax]
    else:
        speed_ax, density_ax, flow_ax = fig.subplots(3, 1, sharex=True)
        axes = [speed_ax, density_ax, flow_ax]
    limits = ylims or {}
    t = series.times
    speed_ax.fill_between(t, series.min_speed, series.max_speed, color="tab:blue", alpha=0.15,
                          linewidth=0, label="min-max")  # fmt: skip
    speed_ax.plot(t, series.mean_speed, color="tab:blue", linewidth=1.2, label="mean")
    speed_ax.set_ylabel("Speed [m/s]")
    speed_ax.set_ylim(*limits.get("speed", (0.0, _top(series.max_speed) * 1.05)))
    speed_ax.legend(loc="best", fontsize="small")
    if closed:
        cars = series.density[np.isfinite(series.density)]
        per_km = f"{float(cars.mean()):.1f} veh/km" if cars.size else "-"
        note = (f"closed network: the density is constant ({per_km}) and no car leaves, "
                "so neither is plotted")  # fmt: skip
        speed_ax.set_xlabel(f"Time [s]\n{note}")
    else:
        density_ax.plot(t, series.density, color="tab:purple", linewidth=1.2)
        density_ax.set_ylabel("Density [veh/km]")
        density_ax.set_ylim(*limits.get("density", (0.0, _top(series.density) * 1.05)))
        if flow.start.size:
            width = np.where(flow.covered > 0, flow.covered, 1.0)
            flow_ax.bar(flow.start, np.nan_to_num(flow.rate), width=width, align="edge",
                        color="tab:green", alpha=0.7, edgecolor="darkgreen")  # fmt: skip
        if "outflow" in limits:
            flow_ax.set_ylim(*limits["outflow"])
        flow_ax.set_ylabel("Outflow [veh/h]")
        flow_ax.set_xlabel("Time [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
        mark_warmup(ax, log)
    road = "the whole network" if series.road == "network" else series.road
    what = "" if closed else ("\n(density: cars per km, all lanes; outflow: cars leaving the "
                              "network per minute, as veh/h)")  # fmt: skip
    fig.suptitle(f"Traffic on {road} - {run_label(log)}{what}", fontsize="medium")
    return _save(fig, out_png)


def shared_traffic_limits(
    pairs: Sequence[tuple[TrafficSeries, Outflow]],
) -> dict[str, tuple[float, float]]:
    """y-ranges for traffic plots compared side by side: 0 to the larger run's maximum."""
    speed = max(_top(s.max_speed) for s, _ in pairs)
    density = max(_top(s.density) for s, _ in pairs)
    rates = [np.nan_to_num(f.rate) for _, f in pairs if f.rate.size]
    outflow = max((float(r.max()) for r in rates), default=0.0)
    return {"speed": (0.0, speed * 1.05), "density": (0.0, density * 1.05),
            "outflow": (0.0, max(outflow * 1.05, 1.0))}  # fmt: skip
