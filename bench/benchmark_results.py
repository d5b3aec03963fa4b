"""Trained benchmark policies: one result file per training run, and the README's table.

``add RUN_DIR...``: score a finished ``flowrun train`` run of a benchmark config (or a policy
folder under ``policies/``) with the protocol of :mod:`flowrun.experiment.benchmark_results` —
``flowrun eval`` in evaluate mode on 5 episodes seeded 1000000-1000004 (never used in
training), and the benchmark's own baseline (``flowrun baseline`` with the benchmark's
overrides, all-human or SUMO's actuated lights) on the same seeds — and write
``bench/results/<benchmark>-<algorithm>-seed<k>.json``.

``policy RUN_DIR``: copy a run's best policy (model, normalisation statistics, config, training
metrics) to ``policies/<benchmark>/``, which ``flowrun eval`` takes like a run folder.

``table``: print the table built from ``bench/results/*.json`` (markdown); ``--readme FILE``
also writes it between the ``<!-- benchmark-results:start/end -->`` markers of FILE.

Run: ``PYTHONPATH=. .venv/bin/python bench/benchmark_results.py add runs/.../<run>/`` (about
2 min per run: 5 policy and 5 baseline episodes twice) then ``... table --readme README.md``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from flowrun.config.yamlio import parse_yaml
from flowrun.experiment import benchmark_results as br
from flowrun.experiment.benchmark import BENCHMARKS, Benchmark

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
FLOWRUN = [sys.executable, "-m", "flowrun.cli.main"]
START, END = "<!-- benchmark-results:start -->", "<!-- benchmark-results:end -->"


def _only(folder: Path, pattern: str) -> Path:
    found = sorted(folder.glob(pattern))
    if not found:
        raise SystemExit(f"error: nothing matches {folder}/{pattern}")
    return found[-1]


def _run(cmd: list[str]) -> None:
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def _config(run_dir: Path) -> dict[str, Any]:
    data, _ = parse_yaml((run_dir / "config.yaml").read_text(), str(run_dir / "config.yaml"))
    if not isinstance(data, dict):
        raise SystemExit(f"error: {run_dir}/config.yaml is not a mapping")
    return data


def baseline_values(bench: Benchmark, config: Path, results: Path) -> list[float]:
    """The benchmark's baseline on the evaluation seeds (cached in ``<name>-baseline.json``)."""
    cache = results / f"{bench.name}-baseline.json"
    if cache.is_file():
        values: list[float] = json.loads(cache.read_text())["values"]
        return values
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [*FLOWRUN, "baseline", str(config), "--runs", str(br.EVAL_EPISODES),
               "--seed", str(br.EVAL_SEED), "--no-record", "--out", tmp]  # fmt: skip
        for item in bench.baseline:
            cmd += ["--set", item]
        _run(cmd)
        metrics = json.loads(_only(Path(tmp), "*/*/metrics.json").read_text())
    values = br.baseline_values(bench, metrics)
    command = " ".join(["flowrun", *cmd[3:-2]])
    cache.write_text(json.dumps({"benchmark": bench.name, "seeds": br.eval_seeds(),
                                 "values": values, "command": command}, indent=1) + "\n")
    return values


def add(run_dir: Path, results: Path, model: str) -> Path:
    """Score one training run and write its result file."""
    cfg = _config(run_dir)
    name = str(cfg.get("name"))
    if name not in BENCHMARKS:
        raise SystemExit(f"error: {run_dir} trained '{name}', not one of Flow's benchmarks")
    bench = BENCHMARKS[name]
    train_metrics = json.loads((run_dir / "metrics.json").read_text())
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [*FLOWRUN, "eval", str(run_dir), "--episodes", str(br.EVAL_EPISODES),
               "--seed", str(br.EVAL_SEED), "--set", "env.evaluate=true", "--model", model,
               "--out", tmp]  # fmt: skip
        _run(cmd)
        policy = br.policy_values(bench, json.loads(_only(Path(tmp), "*/metrics.json").read_text()))
    config = run_dir / "config.yaml"
    baseline = baseline_values(bench, config, results)
    commands = [" ".join(["flowrun", *cmd[3:-2]])]
    record = br.make_record(bench, train_metrics, cfg.get("train", {}), policy, baseline,
                            commands, model)  # fmt: skip
    path = results / br.result_name(name, str(record["algorithm"]), int(record["train_seed"]))
    path.write_text(json.dumps(record, indent=1) + "\n")
    verdict = ("no target" if record["target"] is None
               else f"{record['target']}: {'met' if record['target_met'] else 'not met'}")
    print(f"{path}: policy {record['policy_mean']:.4g} vs baseline {record['baseline_mean']:.4g}"
          f" ({verdict})")
    return path


POLICY_FILES = ("config.yaml", "best_model.zip", "best_vecnormalize.pkl", "metrics.json",
                "status.json")  # fmt: skip


def export_policy(run_dir: Path, policies: Path) -> Path:
    """``policies/<benchmark>/``: the run's best model and what ``flowrun eval`` needs."""
    name = str(_config(run_dir).get("name"))
    folder = policies / name
    folder.mkdir(parents=True, exist_ok=True)
    for file in POLICY_FILES:
        if (run_dir / file).is_file():
            shutil.copyfile(run_dir / file, folder / file)
    print(f"{folder}: {', '.join(sorted(p.name for p in folder.iterdir()))}")
    return folder


def table(results: Path, readme: Path | None) -> str:
    """The markdown table; written into ``readme`` between the markers when given."""
    text = br.markdown_table(br.load_records(results))
    if readme is not None:
        doc = readme.read_text()
        if START not in doc or END not in doc:
            raise SystemExit(f"error: {readme} has no {START} ... {END} markers")
        head, rest = doc.split(START, 1)
        _, tail = rest.split(END, 1)
        readme.write_text(f"{head}{START}\n{text}{END}{tail}")
    return text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p_add = sub.add_parser("add", help="score training runs, write their result files")
    p_add.add_argument("runs", nargs="+", type=Path)
    p_add.add_argument("--model", default="best", choices=("best", "final"))
    p_add.add_argument("--results", type=Path, default=RESULTS)
    p_policy = sub.add_parser("policy", help="copy a run's best policy to policies/<name>/")
    p_policy.add_argument("run", type=Path)
    p_policy.add_argument("--policies", type=Path, default=HERE.parent / "policies")
    p_table = sub.add_parser("table", help="print (and write into the README) the table")
    p_table.add_argument("--results", type=Path, default=RESULTS)
    p_table.add_argument("--readme", type=Path, default=None)
    args = parser.parse_args()
    if args.command == "add":
        args.results.mkdir(parents=True, exist_ok=True)
        for run in args.runs:
            add(run, args.results, args.model)
    elif args.command == "policy":
        export_policy(args.run, args.policies)
    else:
        print(table(args.results, args.readme), end="")


if __name__ == "__main__":
    main()
