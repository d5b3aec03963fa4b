"""The tables the commands print: each fits 80 columns, units in the headers or the caption,
and ``n/a`` where a value is not defined (a return without an RL policy, a speed without
cars, a delay without a finished trip)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from rich import box
from rich.table import Table

#: What a cell shows for a value that is not defined.
NA = "n/a"


def number(x: float | None, spec: str, unit: str = "") -> str:
    """``x`` formatted with ``spec`` (and ``unit``), or ``n/a`` when it is undefined."""
    if x is None or not math.isfinite(x):
        return NA
    return f"{x:{spec}}{unit}"


def new_table(title: str, columns: Iterable[str], caption: str | None = None) -> Table:
    """A table without vertical rules (narrow: fits 80 columns), right-aligned numbers."""
    table = Table(
        title=title, caption=caption, box=box.SIMPLE_HEAD, pad_edge=False, padding=(0, 0, 0, 1),
        show_edge=False,
    )
    for col in columns:
        table.add_column(col, justify="right")
    return table


def is_open(m: Any) -> bool:
    """Whether a run had cars entering or leaving (an open network)."""
    return bool(getattr(m, "departed", 0) or getattr(m, "arrived", 0))


def metrics_table(title: str, rows: list[Any], outflows: Sequence[float] = ()) -> Table:
    """The baseline table: one row per run (:class:`~flowrun.experiment.metrics.RunMetrics`).

    On an open network its headline metric comes first after the run: ``outflows``, each
    run's outflow over its last 500 s as ``metrics.json`` has it (Flow's; leave them out on
    a network with traffic lights, whose signal table measures its throughput).
    """
    opened = bool(outflows) and any(is_open(m) for m in rows)
    columns = ["run", *(("outflow",) if opened else ()), "mean", "2nd half",
               "std", "min", "return", "crashes", "teleports"]  # fmt: skip
    caption = "speeds in m/s; std: across cars"
    if opened:
        caption += "; outflow: veh/h, last 500 s"
    table = new_table(title, columns, caption)
    for i, m in enumerate(rows):
        flow = (number(outflows[i] if i < len(outflows) else None, ".0f"),) if opened else ()
        table.add_row(
            str(m.run),
            *flow,
            number(m.mean_speed, ".3f"),
            number(m.last_half_mean_speed, ".3f"),
            number(m.speed_std, ".3f"),
            number(m.min_speed, ".3f"),
            number(m.episode_return, ".2f"),
            str(m.collisions),
            str(m.teleports),
        )
    return table


def signals_table(title: str, rows: list[Any]) -> Table:
    """The signal-control table: one row per run (:class:`SignalMetrics`)."""
    table = new_table(
        title,
        ("run", "delay s", "trip s", "veh/h out", "queue veh", "waiting at end"),
        "delay, trip: per finished car; queue: mean",
    )
    for i, m in enumerate(rows):
        table.add_row(str(i), number(m.mean_delay, ".1f"), number(m.mean_travel_time, ".1f"),
                      number(m.throughput, ".0f"), number(m.mean_queue, ".2f"),
                      str(m.waiting_at_end))  # fmt: skip
    return table


def compare_table(
    title: str,
    policy: Sequence[Mapping[str, Any]],
    baseline: Sequence[Mapping[str, Any]],
    baseline_label: str = "all-human",
) -> Table:
    """Policy vs its baseline: one row per episode each (dicts of RunMetrics fields, a
    ``mean`` row where there are several). The all-human return is ``n/a``: without the
    policy there is no RL reward to add up; a benchmark's own baseline (``baseline_label``
    ``baseline``) shows its evaluate-mode return, the benchmark's metric (-delay for the
    grids)."""
    table = new_table(
        title,
        ("rollout", "episode", "mean", "2nd half", "std", "2nd half std", "min", "return",
         "crashes"),
        "speeds in m/s; std: across cars, averaged over steps",
    )
    for label, rows in (("policy", policy), (baseline_label, baseline)):
        for m in rows:
            table.add_row(label, str(m["run"]), *_speed_cells(m), _return(label, m),
                          f"{m['collisions']:g}")  # fmt: skip
    return table


def _speed_cells(m: Mapping[str, Any]) -> list[str]:
    keys = ("mean_speed", "last_half_mean_speed", "speed_std", "last_half_speed_std", "min_speed")
    return [number(m[k], ".3f") for k in keys]


def _return(label: str, m: Mapping[str, Any]) -> str:
    return NA if label == "all-human" else number(m["episode_return"], ".1f")
