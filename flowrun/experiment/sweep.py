"""``flowrun sweep``: one baseline run per point of a grid of config values (and seeds).

The plan (:func:`plan_sweep`) is pure: the grid ``--grid key=v1,v2`` (several multiply), the
seeds, a sweep folder named after what is swept, one point per combination. Each point is an
ordinary ``flowrun baseline`` run folder inside the sweep folder, named after its values
(``network.length=230__seed=0``). A point with a completed folder
(:func:`~flowrun.rundir.folders.is_complete`) is skipped when the same sweep runs again, so
an interrupted sweep resumes where it stopped (an interrupted or cut point's folder stays as
it is: the point runs again in ``<label>-1``).

:func:`collect` reads the finished points back; :mod:`flowrun.experiment.sweep_report` writes
the tables and the plot.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import re
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.config.checks import MAX_SEED
from flowrun.config.dump import dump_config
from flowrun.config.model import ExperimentConfig
from flowrun.errors import ConfigError, FlowrunError
from flowrun.experiment.metrics import RunMetrics
from flowrun.rundir.folders import is_complete, read_status, write_json
from flowrun.rundir.lock import FolderLock
from flowrun.suggest import unknown_name

#: Per-run metrics a sweep can plot (``metrics.json`` run rows), besides the signal metrics.
METRICS = (*tuple(f.name for f in fields(RunMetrics) if f.name != "run"), "outflow")
SIGNAL_METRICS = ("mean_delay", "mean_travel_time", "throughput", "mean_queue", "waiting_at_end")
_SAFE = re.compile(r"[^A-Za-z0-9._=\-\[\]]")


@dataclass(frozen=True)
class GridAxis:
    """One ``--grid key=v1,v2,...``: a config key and the values (as typed) it takes."""

    key: str
    values: tuple[str, ...]


@dataclass(frozen=True)
class SweepPoint:
    """One run of the sweep.

    Attributes:
        values: ``(key, value)`` per grid axis, in ``--grid`` order; values as typed.
        seed: the run's seed.
        label: the point's folder name inside the sweep folder.
    """

    values: tuple[tuple[str, str], ...]
    seed: int

    @property
    def overrides(self) -> list[str]:
        """``--set`` values for this point (the seed is passed as ``--seed``)."""
        return [f"{key}={value}" for key, value in self.values]

    @property
    def label(self) -> str:
        """Folder name: ``key=value__key=value__seed=N``, made safe for any file system."""
        raw = "__".join([*(f"{k}={v}" for k, v in self.values), f"seed={self.seed}"])
        safe = _SAFE.sub("_", raw)
        if safe != raw or len(safe) > 120:
            digest = hashlib.sha256(raw.encode()).hexdigest()[:8]
            safe = f"{safe[:110]}-{digest}"
        return safe


@dataclass(frozen=True)
class SweepPlan:
    """Everything a sweep will run.

    Attributes:
        folder: the sweep folder (``<out>/<config-name>/sweep-<digest>``).
        axes: the grid.
        seeds: the seeds of every grid point.
        points: grid x seeds, seeds innermost.
    """

    folder: Path
    axes: tuple[GridAxis, ...]
    seeds: tuple[int, ...]
    points: tuple[SweepPoint, ...]


def split_values(text: str) -> list[str]:
    """Split ``v1,v2,[a,b]`` on the commas outside brackets and braces."""
    parts: list[str] = []
    current: list[str] = []
    depth = 0
    for ch in text:
        if ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append("".join(current).strip())
            current = []
        else:
            current.append(ch)
    parts.append("".join(current).strip())
    return parts


def parse_grid(items: Sequence[str]) -> tuple[GridAxis, ...]:
    """``["key=v1,v2", ...]`` -> grid axes.

    Raises:
        ConfigError: no grid, a malformed item, an empty value, a key given twice.
    """
    if not items:
        raise ConfigError("--grid is required: e.g. --grid network.length=230,260")
    axes: list[GridAxis] = []
    for item in items:
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or not key or not raw.strip():
            raise ConfigError(f"--grid must look like key.path=v1,v2,..., got '{item}'")
        values = split_values(raw)
        if any(not v for v in values):
            raise ConfigError(f"--grid {key}: empty value in '{raw}'")
        if len(set(values)) != len(values):
            raise ConfigError(f"--grid {key}: a value is listed twice in '{raw}'")
        if key in {"sim.seed", "seed"}:
            raise ConfigError(
                f"--grid {key}: seeds are not a grid key; use --seeds N (and --seed S for the "
                "first seed)"
            )
        if any(axis.key == key for axis in axes):
            raise ConfigError(f"--grid {key} is given twice; list all its values in one --grid")
        axes.append(GridAxis(key, tuple(values)))
    return tuple(axes)


def check_metric(metric: str, has_signals: bool = False) -> str:
    """``metric`` if a run row holds it.

    Raises:
        ConfigError: an unknown metric, with a did-you-mean.
    """
    known = METRICS + (SIGNAL_METRICS if has_signals else ())
    if metric not in known:
        raise ConfigError(unknown_name("--metric", metric, known))
    return metric


def sweep_digest(cfg: ExperimentConfig, axes: Sequence[GridAxis], run_args: Sequence[str]) -> str:
    """Names the sweep: the config (seed aside), the grid and the run options.

    The number of seeds is left out, so ``--seeds 3`` after ``--seeds 2`` reuses seeds 0 and 1.
    """
    base = replace(cfg, sim=replace(cfg.sim, seed=0))
    text = json.dumps(
        {
            "config": dump_config(base),
            "grid": [[a.key, list(a.values)] for a in axes],
            "run": list(run_args),
        },
        sort_keys=True,
    )
    return hashlib.sha256(text.encode()).hexdigest()[:10]


def plan_sweep(
    cfg: ExperimentConfig,
    axes: Sequence[GridAxis],
    n_seeds: int,
    out: Path,
    run_args: Sequence[str] = (),
) -> SweepPlan:
    """The sweep folder and its points (grid values x seeds ``seed, seed+1, ...``).

    Args:
        cfg: the base config (``--set`` and ``--seed`` applied), for the folder name and seed.
        axes: the grid.
        n_seeds: seeds per grid point (>= 1).
        out: the ``--out`` folder.
        run_args: the options each run gets (``--steps``, ...): part of the sweep's identity.

    Raises:
        ConfigError: ``n_seeds`` < 1.
    """
    if n_seeds < 1:
        raise ConfigError(f"--seeds must be >= 1, got {n_seeds}")
    first = int(cfg.sim.seed or 0)
    if first + n_seeds - 1 > MAX_SEED:
        raise ConfigError(
            f"--seeds {n_seeds} from seed {first} reaches seed {first + n_seeds - 1}, but seeds "
            f"go up to {MAX_SEED}; use a smaller --seed or fewer --seeds"
        )
    seeds = tuple(range(first, first + n_seeds))
    combos = itertools.product(*[[(a.key, v) for v in a.values] for a in axes])
    points = tuple(SweepPoint(tuple(c), s) for c in combos for s in seeds)
    folder = out / cfg.name / f"sweep-{sweep_digest(cfg, axes, run_args)}"
    return SweepPlan(folder, tuple(axes), seeds, points)


def point_folders(plan: SweepPlan, point: SweepPoint) -> list[Path]:
    """Folders made for ``point`` so far: ``<label>``, ``<label>-1``, ..."""
    base = plan.folder / point.label
    found = [base] if base.is_dir() else []
    n = 1
    while (candidate := base.with_name(f"{base.name}-{n}")).is_dir():
        found.append(candidate)
        n += 1
    return found


def finished_folder(plan: SweepPlan, point: SweepPoint) -> Path | None:
    """The folder of a completed run of ``point``, if any (never a cut or interrupted one)."""
    return next((f for f in point_folders(plan, point) if is_complete(f)), None)


@contextmanager
def locked(plan: SweepPlan) -> Iterator[None]:
    """Hold the sweep folder for this process (``.lock``, released even if it is killed).

    Raises:
        FlowrunError: another process is running the same sweep.
    """
    plan.folder.mkdir(parents=True, exist_ok=True)

    def busy(holder: str) -> FlowrunError:
        return FlowrunError(
            f"this sweep is already running (pid {holder}) in {plan.folder}; wait for it, "
            "or stop it and run the command again"
        )

    with FolderLock(plan.folder / ".lock", busy):
        yield


def write_plan(plan: SweepPlan, argv: Sequence[str]) -> None:
    """``sweep.json``: the grid, the seeds and the command line (rewritten by every run)."""
    plan.folder.mkdir(parents=True, exist_ok=True)
    write_json(
        plan.folder / "sweep.json",
        {
            "grid": {a.key: list(a.values) for a in plan.axes},
            "seeds": list(plan.seeds),
            "points": [p.label for p in plan.points],
            "command": list(argv),
        },
    )


def collect(plan: SweepPlan) -> list[dict[str, Any]]:
    """One row per point: its values, seed, status (``complete``; else how its last attempt
    ended, or ``missing``) and, if it completed, the mean over its runs of every number in
    its ``metrics.json`` run rows."""
    rows = []
    for point in plan.points:
        row: dict[str, Any] = {k: v for k, v in point.values}
        row["seed"] = point.seed
        folder = finished_folder(plan, point)
        tried = point_folders(plan, point)
        if folder is not None:
            row["status"] = "complete"
        else:  # how the last attempt ended: interrupted, failed, cut, running; or never run
            row["status"] = read_status(tried[-1]).state if tried else "missing"
        if folder is not None:
            row["run_dir"] = folder.name
            data = json.loads((folder / "metrics.json").read_text())
            row.update(_mean_rows(data["runs"]))
        rows.append(row)
    return rows


def _mean_rows(runs: list[dict[str, Any]]) -> dict[str, float | None]:
    keys = [k for k in runs[0] if k != "run"] if runs else []
    means: dict[str, float | None] = {}
    for key in keys:
        values = [r.get(key) for r in runs]
        nums = [float(v) for v in values if isinstance(v, (int, float))]
        means[key] = float(np.mean(nums)) if nums and len(nums) == len(values) else None
    return means
