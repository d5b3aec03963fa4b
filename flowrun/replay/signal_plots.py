"""PNG of queues per intersection approach over time, with each approach's signal shaded."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from flowrun.recording import McapLog
from flowrun.replay.plots import _save
from flowrun.replay.signals import GREEN, RED, YELLOW, LightSeries, SignalSeries
from flowrun.replay.summary import run_label

_SIGNAL_COLOURS = {GREEN: "#2ca02c", YELLOW: "#ffbf00", RED: "#d62728"}
_LINE_COLOURS = ("tab:blue", "tab:orange", "tab:purple", "tab:brown", "tab:pink", "tab:gray",
                 "tab:olive", "tab:cyan")  # fmt: skip


def _runs(values: np.ndarray) -> list[tuple[int, int, int]]:
    """``(first index, end index, value)`` of each run of equal consecutive values."""
    if values.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(values)) + 1
    starts = np.concatenate(([0], cuts))
    ends = np.concatenate((cuts, [values.size]))
    return [(int(a), int(b), int(values[a])) for a, b in zip(starts, ends, strict=True)]


def _light_panel(ax: object, light: LightSeries, time: np.ndarray, dt: np.ndarray) -> None:
    """Queue lines from zero up; one band per approach in a strip at the top of the panel
    (above every queue value, never on negative queue values), coloured by its signal."""
    top = max(int(light.queue.max()) if light.queue.size else 0, 1)
    n = max(len(light.approaches), 1)
    strip = min(0.3, 0.07 * n)  # fraction of the panel's height the bands take
    band = strip / n
    span_end = time + np.roll(dt, -1) if time.size > 1 else time + dt
    if time.size > 1:
        span_end[-1] = time[-1] + dt[-1]
    bands = ax.get_xaxis_transform()  # type: ignore[attr-defined]  # x: data, y: panel fraction
    for j, approach in enumerate(light.approaches):
        colour = _LINE_COLOURS[j % len(_LINE_COLOURS)]
        ax.step(time, light.queue[:, j], where="post", color=colour,  # type: ignore[attr-defined]
                linewidth=1.1, label=approach.edge)  # fmt: skip
        low = 1.0 - (j + 1) * band
        bars: dict[int, list[tuple[float, float]]] = {}
        for a, b, value in _runs(light.signal[:, j]):
            if value in _SIGNAL_COLOURS:
                bars.setdefault(value, []).append((time[a], span_end[b - 1] - time[a]))
        for value, spans in bars.items():
            ax.broken_barh(spans, (low, band * 0.85), transform=bands,  # type: ignore[attr-defined]
                           facecolors=_SIGNAL_COLOURS[value], alpha=0.7)  # fmt: skip
        ax.plot(time[:1], [low + band / 2], marker="s", color=colour,  # type: ignore[attr-defined]
                markersize=4, linestyle="", transform=bands)  # fmt: skip
    # queues fill the panel below the strip; the axis has no ticks beyond the largest queue
    ax.set_ylim(0.0, top * 1.05 / (1.0 - strip))  # type: ignore[attr-defined]
    ax.set_yticks([t for t in ax.get_yticks() if 0 <= t <= top * 1.05])  # type: ignore[attr-defined]
    ax.set_title(f"{light.light}: mean queue {light.mean_queue:.2f} veh, delay "  # type: ignore[attr-defined]
                 f"{light.mean_delay:.1f} s/veh", fontsize="small")  # fmt: skip
    ax.legend(loc="center left", fontsize="x-small", ncols=2)  # type: ignore[attr-defined]
    ax.grid(alpha=0.3)  # type: ignore[attr-defined]


def plot_signals(log: McapLog, out_png: str | os.PathLike[str], series: SignalSeries) -> Path:
    """One panel per traffic light: queued cars (speed < 0.1 m/s) per incoming approach over
    time; in a strip at the top of the panel one band per approach (same order as the
    legend), green / yellow / red as that approach's signal showed."""
    n = max(len(series.lights), 1)
    cols = math.ceil(math.sqrt(n))
    rows = math.ceil(n / cols)
    fig = Figure(figsize=(4.2 * cols, 3.2 * rows + 0.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, sharex=True, squeeze=False)).ravel()
    for ax, light in zip(axes, series.lights, strict=False):
        _light_panel(ax, light, series.time, series.dt)
    for ax in axes[len(series.lights) :]:
        ax.set_visible(False)
    for ax in axes[(rows - 1) * cols :]:
        ax.set_xlabel("Time [s]")
    for ax in axes[::cols]:
        ax.set_ylabel("Queue [veh]")
    fig.suptitle(
        f"Queues per approach and their signals - {run_label(log)}\n(bands at the top of each "
        "panel: each approach's signal, in legend order; green / yellow / red)",
        fontsize="medium",
    )
    return _save(fig, out_png)
