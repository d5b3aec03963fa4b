"""What a sweep shows: ``results.csv`` (every number of every point), ``results.md`` (the
points, and with several seeds the mean +- std of each grid point), ``<metric>.png`` (the metric
against the first swept key)."""

from __future__ import annotations

import csv
import itertools
import math
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.experiment.sweep import METRICS, SweepPlan

#: Units of the metrics, for the plot's axis.
UNITS = {
    **{m: "m/s" for m in METRICS if "speed" in m},
    "outflow": "veh/h",
    "throughput": "veh/h",
    "duration": "s",
    "mean_delay": "s",
    "mean_travel_time": "s",
    "mean_queue": "veh",
}


def write_tables(plan: SweepPlan, rows: list[dict[str, Any]], metric: str) -> tuple[Path, Path]:
    """``results.csv`` (every column) and ``results.md`` (the swept values, seed, status and
    the main metrics); returns both paths."""
    columns: list[str] = []
    for row in rows:
        columns += [c for c in row if c not in columns]
    csv_path = plan.folder / "results.csv"
    with csv_path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        for row in rows:
            writer.writerow({c: _exact(row.get(c)) for c in columns})
    shown = [a.key for a in plan.axes] + ["seed", "status"]
    for name in (metric, "mean_speed", "last_half_mean_speed", "outflow", "collisions"):
        if name not in shown:
            shown.append(name)
    lines = _markdown(shown, [[_cell(row.get(c)) for c in shown] for row in rows])
    if len(plan.seeds) > 1:
        lines += ["", f"Mean +- std over seeds {', '.join(map(str, plan.seeds))}:", ""]
        lines += _markdown(*_over_seeds(plan, rows, shown[len(plan.axes) + 2 :]))
    md_path = plan.folder / "results.md"
    md_path.write_text("\n".join(lines) + "\n")
    return csv_path, md_path


def _markdown(header: list[str], cells: list[list[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return lines + ["| " + " | ".join(row) + " |" for row in cells]


def _over_seeds(
    plan: SweepPlan, rows: list[dict[str, Any]], metrics: list[str]
) -> tuple[list[str], list[list[str]]]:
    """One row per grid point: its values, how many seeds completed, mean +- std per metric."""
    keys = [a.key for a in plan.axes]
    cells = []
    for combo in itertools.product(*[a.values for a in plan.axes]):
        done = [r for r in rows if r["status"] == "complete"
                and all(r[k] == v for k, v in zip(keys, combo, strict=True))]  # fmt: skip
        row = [*map(_cell, combo), f"{len(done)}/{len(plan.seeds)}"]
        for metric in metrics:
            got = [float(r[metric]) for r in done if isinstance(r.get(metric), (int, float))]
            row.append(f"{np.mean(got):.4g} +- {np.std(got):.2g}" if got else "")
        cells.append(row)
    return [*keys, "seeds done", *metrics], cells


def _exact(value: Any) -> str:
    """A CSV cell: floats to the last bit (``repr``), missing and non-finite values empty."""
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    return "" if value is None else str(value)


def _cell(value: Any) -> str:
    """A Markdown cell: 6 significant digits, ``|`` escaped."""
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.6g}" if math.isfinite(value) else ""
    return str(value).replace("|", "\\|")


def metric_series(
    plan: SweepPlan, rows: list[dict[str, Any]], metric: str
) -> dict[str, tuple[list[str], list[float], list[float]]]:
    """Per combination of the other keys: (first key's values, mean over seeds, std)."""
    x_key = plan.axes[0].key
    others = [a.key for a in plan.axes[1:]]
    series: dict[str, tuple[list[str], list[float], list[float]]] = {}
    for combo in itertools.product(*[a.values for a in plan.axes[1:]]):
        name = ", ".join(f"{k}={v}" for k, v in zip(others, combo, strict=True)) or metric
        xs, means, stds = [], [], []
        for x in plan.axes[0].values:
            want = {x_key: x, **dict(zip(others, combo, strict=True))}
            got = [
                float(r[metric])
                for r in rows
                if r["status"] == "complete"
                and all(r[k] == v for k, v in want.items())
                and isinstance(r.get(metric), (int, float))
            ]
            if got:
                xs.append(x)
                means.append(float(np.mean(got)))
                stds.append(float(np.std(got)))
        series[name] = (xs, means, stds)
    return series


def plot_metric(plan: SweepPlan, rows: list[dict[str, Any]], metric: str) -> Path:
    """``<metric>.png``: the metric against the first swept key (numeric axis when it can)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.2))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for name, (xs, means, stds) in metric_series(plan, rows, metric).items():
        try:
            x: list[Any] = [float(v) for v in xs]
        except ValueError:
            x = list(xs)
        ax.errorbar(x, means, yerr=stds, marker="o", capsize=3, label=name)
    ax.set_xlabel(plan.axes[0].key)
    ax.set_ylabel(f"{metric} ({UNITS[metric]})" if metric in UNITS else metric)
    ax.set_title(f"{metric} vs {plan.axes[0].key} ({len(plan.seeds)} seed(s) per point)")
    ax.grid(alpha=0.3)
    if len(plan.axes) > 1:
        ax.legend(fontsize="small")
    path = plan.folder / f"{metric}.png"
    fig.savefig(path, dpi=100)
    return path
