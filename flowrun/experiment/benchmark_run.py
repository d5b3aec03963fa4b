"""What ``flowrun benchmark`` runs and where, and reading the results back.

A benchmark run folder ``<out>/benchmark/<timestamp>/`` holds:

* ``baseline/<name>/seed=<s>/``: one ``flowrun baseline`` run folder per benchmark and seed
  (the config, ``--set`` values, then the baseline's overrides, seed ``s``);
* with ``--train``: ``train/<name>/seed=<k>/.../`` the ``flowrun train`` run of each
  benchmark and training seed ``k``, ``policy/<name>/seed=<k>/<timestamp>-<seed>/`` its
  ``flowrun eval`` in evaluate mode on the evaluation seeds
  (:func:`flowrun.experiment.benchmark_results.eval_seeds`, never used in training), and
  ``results/<name>-<algorithm>-seed<k>.json`` its result file; the baselines then run on the
  evaluation seeds too, so policy and baseline see the same episodes;
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

from flowrun.config.dump import config_to_dict
from flowrun.experiment.benchmark import Benchmark, metric_value
from flowrun.experiment.benchmark_results import (
    eval_seeds,
    interval95,
    make_record,
    policy_values,
    result_name,
)
from flowrun.loading.loader import load_config
from flowrun.rundir.folders import is_complete, read_status
from flowrun.rundir.safeio import write_json

#: The command that starts a flowrun command in a child process.
FLOWRUN = (sys.executable, "-m", "flowrun.cli.main")


@dataclass(frozen=True)
class BenchmarkPlan:
    """Everything ``flowrun benchmark`` will run.

    Attributes:
        folder: the benchmark run folder.
        benchmarks: the chosen benchmarks, in Flow's order.
        seeds: the seeds of every baseline; with ``train`` the training seeds (the baselines
            and policies then run on the evaluation seeds, :attr:`baseline_seeds`).
        configs: the folder holding ``<name>.yaml``.
        sets: the ``--set`` values applied to every benchmark (before the baseline's own).
        train: also train each benchmark's policy and score it.
        record: write MCAP logs of the baseline runs.
        deadline: with ``--budget``: when every training stops at the latest (ISO 8601).
    """

    folder: Path
    benchmarks: tuple[Benchmark, ...]
    seeds: tuple[int, ...]
    configs: Path
    sets: tuple[str, ...] = ()
    train: bool = False
    record: bool = False
    deadline: str | None = None

    @property
    def baseline_seeds(self) -> tuple[int, ...]:
        """The baselines' seeds: ``seeds``, or with ``train`` the evaluation seeds."""
        return tuple(eval_seeds()) if self.train else self.seeds


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


def train_command(plan: BenchmarkPlan, bench: Benchmark, seed: int) -> list[str]:
    """The ``flowrun train`` command of one benchmark and training seed."""
    cmd = [*FLOWRUN, "train", str(bench.config_path(plan.configs)), *_sets(plan.sets)]
    out = plan.folder / "train" / bench.name / f"seed={seed}"
    cmd += ["--seed", str(seed), "--out", str(out)]
    return cmd if plan.deadline is None else [*cmd, "--deadline", plan.deadline]


def train_run(plan: BenchmarkPlan, bench: Benchmark, seed: int) -> Path | None:
    """The completed ``flowrun train`` run folder of ``bench`` and ``seed``, if any."""
    parent = plan.folder / "train" / bench.name / f"seed={seed}"
    found = sorted(p.parent for p in parent.glob("*/*/config.yaml"))
    return next((p for p in found if is_complete(p)), None)


def policy_folder(plan: BenchmarkPlan, bench: Benchmark, seed: int) -> Path:
    """``<folder>/policy/<name>/seed=<seed>``: the evaluations of training seed ``seed``."""
    return plan.folder / "policy" / bench.name / f"seed={seed}"


def policy_command(plan: BenchmarkPlan, bench: Benchmark, seed: int, run_dir: Path) -> list[str]:
    """The ``flowrun eval`` of a trained policy on the evaluation seeds, in evaluate mode."""
    seeds = eval_seeds()
    return [*FLOWRUN, "eval", str(run_dir), "--episodes", str(len(seeds)),
            "--set", "env.evaluate=true", "--seed", str(seeds[0]),
            "--out", str(policy_folder(plan, bench, seed))]  # fmt: skip


def summary(values: Sequence[float]) -> dict[str, float | None]:
    """Mean and (population) standard deviation; ``None`` for no values."""
    if not values:
        return {"mean": None, "std": None}
    return {"mean": float(np.mean(values)), "std": float(np.std(values))}


def _baseline(plan: BenchmarkPlan, bench: Benchmark) -> dict[str, Any]:
    runs: list[dict[str, Any]] = []
    for seed in plan.baseline_seeds:
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


def _policy(plan: BenchmarkPlan, bench: Benchmark, baseline: list[float]) -> dict[str, Any]:
    """Each training seed's policy scored on the evaluation seeds (and its result file); the
    values are the seeds' means, with their mean, std and 95 % interval."""
    seeds: list[dict[str, Any]] = []
    for seed in plan.seeds:
        seeds.append(_policy_seed(plan, bench, seed, baseline))
    values = [s["mean"] for s in seeds if s.get("mean") is not None]
    done = "complete" if len(values) == len(plan.seeds) else "incomplete"
    return {"status": done if values else "not trained", "seeds": seeds, "values": values,
            **summary(values), "ci95": interval95(values)}  # fmt: skip


def _policy_seed(
    plan: BenchmarkPlan, bench: Benchmark, seed: int, baseline: list[float]
) -> dict[str, Any]:
    run_dir = train_run(plan, bench, seed)
    if run_dir is None:
        return {"seed": seed, "status": "not trained"}
    out: dict[str, Any] = {"seed": seed, "train_run": str(run_dir.relative_to(plan.folder))}
    for metrics in sorted(policy_folder(plan, bench, seed).glob("*/metrics.json")):
        data = json.loads(metrics.read_text())
        if data.get("status") != "complete":
            continue
        values = policy_values(bench, data)
        train_metrics = json.loads((run_dir / "metrics.json").read_text())
        recipe = json.loads(json.dumps(config_to_dict(load_config(run_dir / "config.yaml"))))
        command = " ".join(["flowrun", *policy_command(plan, bench, seed, run_dir)[3:]])
        record = make_record(bench, train_metrics, recipe.get("train") or {}, values, baseline,
                             [command])
        name = result_name(bench.name, str(record["algorithm"]), seed)
        (plan.folder / "results").mkdir(exist_ok=True)
        write_json(plan.folder / "results" / name, record)
        return {**out, "status": "complete", "episodes": values, **summary(values),
                "eval": str(metrics.parent.relative_to(plan.folder)),
                "result": f"results/{name}"}  # fmt: skip
    return {**out, "status": "not evaluated"}


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
            row["policy"] = _policy(plan, bench, row["baseline"]["values"])
        rows.append(row)
    return rows
