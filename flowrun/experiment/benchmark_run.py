"""What ``flowrun benchmark`` runs and where, and reading the results back.

A benchmark run folder ``<out>/benchmark/<timestamp>/`` holds:

* ``baseline/<name>/seed=<s>/``: one ``flowrun baseline`` run folder per benchmark and seed
  (the config, ``--set`` values, then the baseline's overrides, seed ``s``);
* with ``--train``: ``train/<name>/.../`` the ``flowrun train`` run of each benchmark (seeded
  with the first seed), and ``policy/<name>/<timestamp>-<seed>/`` its ``flowrun eval`` over
  the same seeds in evaluate mode;
* ``results.json``, ``results.md`` and ``benchmark.png``
  (:mod:`flowrun.experiment.benchmark_report`).

Every run is its own process (libsumo runs one simulation per process); the commands are
built here and run by the sweep's process pool.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.experiment.benchmark import Benchmark, metric_value
from flowrun.rundir.folders import is_complete, read_status

#: The command that starts a flowrun command in a child process.
FLOWRUN = (sys.executable, "-m", "flowrun.cli.main")


@dataclass(frozen=True)
class BenchmarkPlan:
    """Everything ``flowrun benchmark`` will run.

    Attributes:
        folder: the benchmark run folder.
        benchmarks: the chosen benchmarks, in Flow's order.
        seeds: the seeds of every baseline (and of the policy's evaluation episodes).
        configs: the folder holding ``<name>.yaml``.
        sets: the ``--set`` values applied to every benchmark (before the baseline's own).
        train: also train each benchmark's policy and score it.
        record: write MCAP logs of the baseline runs.
    """

    folder: Path
    benchmarks: tuple[Benchmark, ...]
    seeds: tuple[int, ...]
    configs: Path
    sets: tuple[str, ...] = ()
    train: bool = False
    record: bool = False


def folder_name(now: datetime | None = None) -> str:
    """``<timestamp>`` (UTC, to the second) of a new benchmark run folder."""
    return (now or datetime.now(UTC)).strftime("%Y%m%d-%H%M%S")


def baseline_folder(plan: BenchmarkPlan, bench: Benchmark, seed: int) -> Path:
    """``<folder>/baseline/<name>/seed=<seed>``."""
    return plan.folder / "baseline" / bench.name / f"seed={seed}"


def _sets(items: Sequence[str]) -> list[str]:
    return [arg for item in items for arg in ("--set", item)]


def baseline_command(plan: BenchmarkPlan, bench: Benchmark, seed: int) -> list[str]:
    """The ``flowrun baseline`` command of one benchmark and seed."""
    cmd = [*FLOWRUN, "baseline", str(bench.config_path(plan.configs))]
    cmd += _sets([*plan.sets, *bench.baseline])
    cmd += ["--seed", str(seed), "--out", str(plan.folder), "--runs", "1"]
    cmd += ["--folder", str(baseline_folder(plan, bench, seed))]
    return cmd if plan.record else [*cmd, "--no-record"]


def train_command(plan: BenchmarkPlan, bench: Benchmark) -> list[str]:
    """The ``flowrun train`` command of one benchmark (seeded with the first seed)."""
    cmd = [*FLOWRUN, "train", str(bench.config_path(plan.configs)), *_sets(plan.sets)]
    return [*cmd, "--seed", str(plan.seeds[0]), "--out", str(plan.folder / "train" / bench.name)]


def train_run(plan: BenchmarkPlan, bench: Benchmark) -> Path | None:
    """The completed ``flowrun train`` run folder of ``bench``, if any."""
    parent = plan.folder / "train" / bench.name
    found = sorted(p.parent for p in parent.glob("*/*/config.yaml"))
    return next((p for p in found if is_complete(p)), None)


def policy_command(plan: BenchmarkPlan, bench: Benchmark, run_dir: Path) -> list[str]:
    """The ``flowrun eval`` of a trained policy: one episode per seed, in evaluate mode."""
    return [*FLOWRUN, "eval", str(run_dir), "--episodes", str(len(plan.seeds)),
            "--set", "env.evaluate=true", "--seed", str(plan.seeds[0]),
            "--out", str(plan.folder / "policy" / bench.name)]  # fmt: skip


def summary(values: Sequence[float]) -> dict[str, float | None]:
    """Mean and (population) standard deviation; ``None`` for no values."""
    if not values:
        return {"mean": None, "std": None}
    return {"mean": float(np.mean(values)), "std": float(np.std(values))}


def _baseline(plan: BenchmarkPlan, bench: Benchmark) -> dict[str, Any]:
    runs: list[dict[str, Any]] = []
    for seed in plan.seeds:
        folder = baseline_folder(plan, bench, seed)
        entry: dict[str, Any] = {"seed": seed, "folder": str(folder.relative_to(plan.folder))}
        if is_complete(folder):
            row = json.loads((folder / "metrics.json").read_text())["runs"][0]
            entry.update(status="complete", value=metric_value(bench.metric, row))
        else:
            entry.update(status=read_status(folder).state if folder.is_dir() else "missing",
                         value=None)  # fmt: skip
        runs.append(entry)
    values = [r["value"] for r in runs if r["value"] is not None]
    return {"runs": runs, "values": values, **summary(values), "sets": list(bench.baseline)}


def _policy(plan: BenchmarkPlan, bench: Benchmark) -> dict[str, Any]:
    run_dir = train_run(plan, bench)
    if run_dir is None:
        return {"status": "not trained", "values": [], **summary([])}
    out: dict[str, Any] = {"train_run": str(run_dir.relative_to(plan.folder))}
    for metrics in sorted((plan.folder / "policy" / bench.name).glob("*/metrics.json")):
        data = json.loads(metrics.read_text())
        if data.get("status") == "complete":
            values = [metric_value(bench.metric, row, policy=True) for row in data["policy"]]
            kept = [v for v in values if v is not None]
            return {**out, "status": "complete", "values": kept, **summary(kept),
                    "eval": str(metrics.parent.relative_to(plan.folder))}  # fmt: skip
    return {**out, "status": "not evaluated", "values": [], **summary([])}


def collect(plan: BenchmarkPlan) -> list[dict[str, Any]]:
    """One row per benchmark: its metric, the baseline's value per seed with mean and std,
    Flow's reference, and (with ``--train``) the policy's scores."""
    rows = []
    for bench in plan.benchmarks:
        row: dict[str, Any] = {
            "benchmark": bench.name,
            "family": bench.family,
            "metric": bench.metric.label,
            "unit": bench.metric.unit,
            "reference": bench.reference,
            "reference_note": bench.reference_note,
            "baseline": _baseline(plan, bench),
        }
        if plan.train:
            row["policy"] = _policy(plan, bench)
        rows.append(row)
    return rows
