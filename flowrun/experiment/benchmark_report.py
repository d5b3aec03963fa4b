"""What ``flowrun benchmark`` writes: ``results.json`` (everything), ``results.md`` (the table
and notes) and ``benchmark.png`` (each benchmark's baseline, policy and Flow's reference, one
panel per family)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from flowrun.experiment.benchmark import FAMILIES
from flowrun.experiment.benchmark_run import BenchmarkPlan
from flowrun.rundir.folders import write_json


def mean_std(part: dict[str, Any] | None) -> str:
    """``mean ± std (n=...)`` of a baseline/policy entry (the std to 2 significant digits, ``n``
    shown unless 1); ``-`` when it has no value."""
    if not part or part.get("mean") is None:
        return "-"
    n = len(part["values"])
    return f"{_num(part['mean'])} ± {part['std']:.2g}" + (f" (n={n})" if n != 1 else "")


def reference_text(row: dict[str, Any]) -> str:
    """Flow's reference, or ``none *`` (see :func:`notes`)."""
    if row["reference"] is None:
        return "none *" if row["reference_note"] else "none"
    return _num(float(row["reference"]))


def notes(rows: Sequence[dict[str, Any]]) -> list[str]:
    """``* benchmarks: why`` for each distinct reason a reference is missing."""
    reasons: dict[str, list[str]] = {}
    for row in rows:
        if row["reference"] is None and row["reference_note"]:
            reasons.setdefault(row["reference_note"], []).append(row["benchmark"])
    return [f"* {', '.join(names)}: {why}" for why, names in reasons.items()]


def table_rows(rows: Sequence[dict[str, Any]], train: bool) -> tuple[list[str], list[list[str]]]:
    """Header and cells of the results table (shared by the terminal and ``results.md``)."""
    header = ["benchmark", "metric", "baseline (mean ± std)", "Flow's reference"]
    if train:
        header.append("policy (mean ± std)")
    cells = []
    for row in rows:
        line = [row["benchmark"], f"{row['metric']} ({row['unit']})", mean_std(row["baseline"]),
                reference_text(row)]  # fmt: skip
        if train:
            line.append(mean_std(row.get("policy")))
        cells.append(line)
    return header, cells


def write_results(
    plan: BenchmarkPlan, rows: list[dict[str, Any]], argv: Sequence[str], status: str
) -> tuple[Path, Path, Path | None]:
    """``results.json``, ``results.md`` and (if any value exists) ``benchmark.png``."""
    data = {
        "status": status,
        "command": list(argv),
        "seeds": list(plan.seeds),
        "sets": list(plan.sets),
        "configs": str(plan.configs),
        "train": plan.train,
        "benchmarks": rows,
    }
    json_path = plan.folder / "results.json"
    write_json(json_path, data)
    header, cells = table_rows(rows, plan.train)
    lines = [
        f"# flowrun benchmark ({status})",
        "",
        f"Seeds {', '.join(map(str, plan.seeds))}; --set {' '.join(plan.sets) or '(none)'}.",
        "",
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
        *("| " + " | ".join(c.replace("|", "\\|") for c in line) + " |" for line in cells),
        "",
        "Baseline: Flow's non-RL baseline of each benchmark (flow/benchmarks/baselines/), "
        "mean ± std over the seeds. Flow's reference: the score flow/benchmarks/create_movies.sh "
        "expects of a trained policy (it passes at 95 %).",
        *(["", *notes(rows)] if notes(rows) else []),
        "",
        "Each baseline is its benchmark's config with these --set overrides (after the run's):",
        "",
        *(f"- {row['benchmark']}: " + " ".join(f"`--set {s}`" for s in row["baseline"]["sets"])
          for row in rows),
    ]
    md_path = plan.folder / "results.md"
    md_path.write_text("\n".join(lines) + "\n")
    return json_path, md_path, plot_results(plan, rows)


def plot_title(plan: BenchmarkPlan) -> str:
    """The benchmark plot's title: seeds, and every ``--set`` the runs had (a shortened
    ``env.horizon`` changes what the numbers mean)."""
    title = f"flowrun benchmark: {len(plan.seeds)} seed(s)"
    if plan.sets:
        title += "\n--set " + " --set ".join(plan.sets)
    return title


def plot_results(plan: BenchmarkPlan, rows: Sequence[dict[str, Any]]) -> Path | None:
    """``benchmark.png``: one panel per family; bars for the baseline (and policy) with their
    std over seeds, a black tick at Flow's reference. ``None`` when nothing has a value."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    families = [f for f in FAMILIES if any(r["family"] == f and _has_value(r) for r in rows)]
    if not families:
        return None
    fig = Figure(figsize=(3.2 * len(families) + 1, 4.0))
    FigureCanvasAgg(fig)
    for i, family in enumerate(families):
        ax = fig.add_subplot(1, len(families), i + 1)
        mine = [r for r in rows if r["family"] == family]
        xs = list(range(len(mine)))
        width = 0.38 if plan.train else 0.7
        parts = [("baseline", "tab:blue", 0.0)]
        if plan.train:
            parts = [("baseline", "tab:blue", -width / 2), ("policy", "tab:orange", width / 2)]
        for key, color, shift in parts:
            means = [_or_nan((r.get(key) or {}).get("mean")) for r in mine]
            stds = [_or_nan((r.get(key) or {}).get("std")) for r in mine]
            ax.bar([x + shift for x in xs], means, width, yerr=stds, capsize=3, color=color,
                   label=key)  # fmt: skip
        refs = [(x, r["reference"]) for x, r in zip(xs, mine, strict=True) if r["reference"]]
        if refs:
            ax.scatter([x for x, _ in refs], [v for _, v in refs], marker="_", s=400,
                       color="black", label="Flow's reference", zorder=3)  # fmt: skip
        ax.set_xticks(xs, [r["benchmark"] for r in mine], rotation=30, fontsize="small")
        ax.set_ylabel(f"{mine[0]['metric']} ({mine[0]['unit']})")
        ax.grid(axis="y", alpha=0.3)
    # one legend for all panels, beside the title: inside a panel it covered the reference ticks
    handles, labels = fig.axes[0].get_legend_handles_labels()
    for other in fig.axes[1:]:
        for h, label in zip(*other.get_legend_handles_labels(), strict=True):
            if label not in labels:
                handles.append(h)
                labels.append(label)
    fig.legend(handles, labels, loc="upper right", fontsize="small", ncols=len(labels))
    fig.suptitle(plot_title(plan), x=0.01, ha="left", fontsize="medium")
    fig.tight_layout(rect=(0, 0, 1, 0.9))
    path = plan.folder / "benchmark.png"
    fig.savefig(path, dpi=100)
    return path


def _has_value(row: dict[str, Any]) -> bool:
    return any((row.get(k) or {}).get("mean") is not None for k in ("baseline", "policy"))


def _or_nan(value: float | None) -> float:
    return float("nan") if value is None else float(value)


def _num(value: float) -> str:
    """4 significant digits, no exponent for the sizes benchmarks have."""
    return f"{value:.4g}" if abs(value) < 1e5 else f"{value:.0f}"
