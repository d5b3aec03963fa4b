"""Trained-policy results of Flow's benchmarks: the evaluation protocol, one small file per
training run, and the table built from those files.

Protocol: a policy trained with seed ``k`` is rolled out in evaluate mode on
:data:`EVAL_EPISODES` episodes seeded ``EVAL_SEED, EVAL_SEED + 1, ...`` — seeds no training
uses (training envs start from ``k + rank``, the periodic evaluation from ``k + 10000``) —
and the benchmark's own baseline (:attr:`Benchmark.baseline`: all-human, or SUMO's actuated
lights for the grids) runs on the same seeds. A result file holds both, per episode; the table
gives, per benchmark, the mean over training seeds of each policy's mean and a 95 % Student-t
interval over those seeds, beside the baseline and the paper's numbers.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.experiment.benchmark import BENCHMARKS, Benchmark, metric_value

#: First evaluation seed and number of evaluation episodes of every policy and baseline.
EVAL_SEED = 1_000_000
EVAL_EPISODES = 5


@dataclass(frozen=True)
class Target:
    """What a trained policy must reach.

    Attributes:
        text: the target in words (``>= 7.3 m/s``).
        absolute: a fixed value to reach (``None``: relative to the baseline).
        gain: relative improvement over the baseline's mean (0.05 = 5 % better).
    """

    text: str
    absolute: float | None = None
    gain: float = 0.0

    def threshold(self, baseline: float | None) -> float | None:
        """The value to reach (higher is better for every metric here)."""
        if self.absolute is not None:
            return self.absolute
        if baseline is None:
            return None
        return baseline + self.gain * abs(baseline)  # -delay: 5 % less delay is +0.05|b|

    def met(self, value: float | None, baseline: float | None) -> bool | None:
        """Whether ``value`` reaches the target (``None`` when it cannot be decided)."""
        limit = self.threshold(baseline)
        return None if value is None or limit is None else value >= limit


TARGETS: dict[str, Target] = {
    "figureeight0": Target(">= 7.3 m/s", absolute=7.3),
    "merge0": Target(">= 13.0 m/s", absolute=13.0),
    "grid0": Target("mean delay >= 5 % below actuated lights", gain=0.05),
    "bottleneck0": Target("outflow >= 10 % above all-human", gain=0.10),
}

#: Flow's ``flow/benchmarks/create_movies.sh`` passes a trained policy at 95 % of its
#: reference (:attr:`Benchmark.reference`, ``PERF_GUARANTEE``). The table shows that check
#: beside the benchmarks without a target of :data:`TARGETS`, as a reference, not a target.
FLOW_CHECK_PASS = 0.95


def flow_check_reached(bench: Benchmark, score: float | None) -> bool | None:
    """Whether ``score`` passes Flow's check (``None``: no score or no usable reference)."""
    if score is None or bench.reference is None:
        return None
    return score >= FLOW_CHECK_PASS * bench.reference


#: The paper's (Vinitsky et al., CoRL 2018, Table 1) all-human score and best learned score.
PAPER: dict[str, tuple[str, str]] = {
    "figureeight0": ("4.18 ± 0.09", "TRPO 8.26 ± 0.10"),
    "figureeight1": ("4.18 ± 0.09", "ARS 6.43 ± 0.01"),
    "figureeight2": ("4.18 ± 0.09", "ES 5.96 ± 0.00"),
    "merge0": ("7.39 ± 0.55", "TRPO 14.95 ± 0.12"),
    "merge1": ("7.39 ± 0.55", "ES 17.29 ± 0.40"),
    "merge2": ("7.39 ± 0.55", "ES 17.36 ± 0.48"),
    "grid0": ("280.8 ± 1.5 (reward)", "PPO 296.8 ± 5.3 (reward)"),
    "grid1": ("276.8 ± 1.7 (reward)", "PPO 296.2 ± 2.0 (reward)"),
    "bottleneck0": ("1023 ± 263", "ES 1360 ± 200"),
    "bottleneck1": ("1135 ± 319", "ES 1378 ± 192"),
    "bottleneck2": ("1889 ± 252", "ES 2324 ± 264"),
}

# Student's t, two-sided 95 %, by degrees of freedom.
_T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306,
        9: 2.262, 10: 2.228}  # fmt: skip


def eval_seeds() -> list[int]:
    """The evaluation episodes' reset seeds."""
    return [EVAL_SEED + i for i in range(EVAL_EPISODES)]


def interval95(values: Sequence[float]) -> float | None:
    """Half-width of the 95 % Student-t interval of the mean (``None`` below 2 values)."""
    n = len(values)
    if n < 2:
        return None
    t = _T95.get(n - 1, 1.96)
    return float(t * np.std(values, ddof=1) / math.sqrt(n))


def result_name(benchmark: str, algorithm: str, seed: int) -> str:
    """``<benchmark>-<algorithm>-seed<k>.json`` (the algorithm in lower case)."""
    return f"{benchmark}-{algorithm.lower()}-seed{seed}.json"


def policy_values(bench: Benchmark, eval_metrics: Mapping[str, Any]) -> list[float]:
    """The metric of each policy episode of a ``flowrun eval`` ``metrics.json``."""
    rows = eval_metrics.get("policy", [])
    values = [metric_value(bench.metric, row, policy=True) for row in rows]
    return [v for v in values if v is not None]


def baseline_values(bench: Benchmark, baseline_metrics: Mapping[str, Any]) -> list[float]:
    """The metric of each run of a ``flowrun baseline`` ``metrics.json``."""
    values = [metric_value(bench.metric, row) for row in baseline_metrics.get("runs", [])]
    return [v for v in values if v is not None]


def make_record(
    bench: Benchmark,
    train_metrics: Mapping[str, Any],
    train_config: Mapping[str, Any],
    policy: Sequence[float],
    baseline: Sequence[float],
    commands: Sequence[str],
    model: str = "best",
) -> dict[str, Any]:
    """The result file of one training run (plain data)."""
    target = TARGETS.get(bench.name)
    p_mean = float(np.mean(policy)) if policy else None
    b_mean = float(np.mean(baseline)) if baseline else None
    return {
        "benchmark": bench.name,
        "algorithm": train_metrics.get("algorithm"),
        "train_seed": train_metrics.get("seed"),
        "metric": bench.metric.label,
        "unit": bench.metric.unit,
        "recipe": train_config,
        "timesteps": train_metrics.get("timesteps"),
        "train_status": train_metrics.get("status"),
        "stopped_at_budget": bool(train_metrics.get("stopped_at_budget")),
        "train_wall_s": train_metrics.get("wall_clock_s"),
        "model": model,
        "eval_seeds": eval_seeds()[: len(policy)],
        "policy": list(policy),
        "policy_mean": p_mean,
        "baseline": list(baseline),
        "baseline_mean": b_mean,
        "baseline_sets": list(bench.baseline),
        "target": None if target is None else target.text,
        "target_met": None if target is None else target.met(p_mean, b_mean),
        "commands": list(commands),
    }


def load_records(folder: Path) -> list[dict[str, Any]]:
    """Every result file of ``folder`` (``*-seed*.json``), sorted by name."""
    return [json.loads(p.read_text()) for p in sorted(folder.glob("*-seed*.json"))]


def _fmt(value: float | None, digits: int = 4) -> str:
    if value is None:
        return "–"
    return f"{value:.{digits}g}" if abs(value) < 1e4 else f"{value:.0f}"


def table_rows(records: Sequence[Mapping[str, Any]]) -> list[list[str]]:
    """One row per benchmark and algorithm, in Flow's order (see :data:`TABLE_HEADER`)."""
    groups: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for rec in records:
        groups.setdefault((rec["benchmark"], str(rec["algorithm"])), []).append(rec)
    order = list(BENCHMARKS)
    rows = []
    for (name, algo), recs in sorted(groups.items(), key=lambda kv: (order.index(kv[0][0]),
                                                                       kv[0][1])):  # fmt: skip
        means = [r["policy_mean"] for r in recs if r["policy_mean"] is not None]
        base = [v for r in recs for v in r["baseline"]]
        b_mean = float(np.mean(base)) if base else None
        half = interval95(means)
        learned = _fmt(float(np.mean(means))) if means else "–"
        if half is not None:
            learned += f" ± {_fmt(half, 2)}"
        walls = [r["train_wall_s"] / 60 for r in recs if r.get("train_wall_s")]
        paper = PAPER.get(name, ("–", "–"))
        rows.append([
            name,
            f"{recs[0]['metric']} ({recs[0]['unit']})",
            _fmt(b_mean),
            f"{algo}: {learned}",
            ", ".join(_seed_text(r) for r in recs),
            _goal_text(name, recs, b_mean),
            f"{max(walls):.0f}" if walls else "–",
            paper[0],
            paper[1],
        ])
    return rows


def _goal_text(name: str, recs: Sequence[Mapping[str, Any]], baseline: float | None) -> str:
    """The target and how many seeds meet it; without a target, Flow's check (a reference,
    not a target) and how many seeds, and whether the baseline, reach it."""
    target = TARGETS.get(name)
    if target is not None:
        met = sum(1 for r in recs if r.get("target_met"))
        return f"{target.text}: {met} of {len(recs)}"
    bench = BENCHMARKS[name]
    if bench.reference is None:
        return "no target; Flow has no usable check" if bench.reference_note else "–"
    ref = bench.reference
    value = f"{ref:.1f}" if abs(ref) < 100 else f"{ref:.0f}"
    reached = sum(1 for r in recs if flow_check_reached(bench, r.get("policy_mean")))
    text = (f"no target; Flow's check >= {FLOW_CHECK_PASS * 100:g} % of {value} "
            f"{bench.metric.unit}: {reached} of {len(recs)} reach it")  # fmt: skip
    return text + (" (so does the baseline)" if flow_check_reached(bench, baseline) else "")


def _seed_text(rec: Mapping[str, Any]) -> str:
    """``0``, or ``0 (stopped at 1.34M of 2.1M steps)`` for a training that did not finish
    (``... at the budget``: stopped by ``--budget``)."""
    budget = bool(rec.get("stopped_at_budget"))
    if rec.get("train_status") in (None, "complete") and not budget:
        return str(rec["train_seed"])
    total = (rec.get("recipe") or {}).get("total_timesteps")
    of = f" of {total / 1e6:.3g}M" if isinstance(total, int | float) else ""
    done = (rec.get("timesteps") or 0) / 1e6
    why = " at the budget" if budget else ""
    return f"{rec['train_seed']} (stopped{why} at {done:.3g}M{of} steps)"


TABLE_HEADER = [
    "benchmark", "metric", "flowrun baseline", "flowrun learned (mean ± 95 %)",
    "training seeds", "target: seeds meeting it", "wall min/seed", "paper all-human",
    "paper best learned",
]  # fmt: skip


def markdown_table(records: Sequence[Mapping[str, Any]]) -> str:
    """The README's results table."""
    lines = ["| " + " | ".join(TABLE_HEADER) + " |", "|" + "---|" * len(TABLE_HEADER)]
    lines += ["| " + " | ".join(row) + " |" for row in table_rows(records)]
    return "\n".join(lines) + "\n"
