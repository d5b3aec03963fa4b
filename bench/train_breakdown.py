"""Where a training run's time goes: start-up, env stepping, policy inference, updates, evaluation.

Trains the config (``flowrun.training.train``, as ``flowrun train`` does, without the closing
evaluation) and prints the parts of its wall-clock time, or prints them for a finished run
folder (its ``metrics.json``). The learning curve of the periodic evaluations follows
(last-half mean speed of the evaluation episodes, which pick ``best_model.zip``).

    .venv/bin/python bench/train_breakdown.py [--config configs/ring_wave.yaml] [--seed 0]
        [--set train.total_timesteps=60000] [--out runs/train_breakdown]
    .venv/bin/python bench/train_breakdown.py --run runs/ring_wave/<run>/
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from flowrun.training.periodic_eval import EVAL_LOG, EVALUATIONS, EvalHistory

PARTS = (
    ("startup_s", "start-up (env processes, model, eval env)"),
    ("env_wait_s", "env stepping (waiting for the env processes)"),
    ("inference_s", "policy inference + SB3 rollout loop"),
    ("update_s", "gradient updates"),
    ("evaluation_s", "evaluation"),
    ("checkpoints_s", "checkpoints"),
    ("finish_s", "finish (final save, close)"),
)


def print_breakdown(run_dir: Path) -> None:
    """Print the timing table and the evaluation curve of a run folder."""
    metrics = json.loads((run_dir / "metrics.json").read_text())
    timing = metrics["timing"]
    total = timing["total_s"]
    steps = metrics["timesteps"] - (metrics.get("resumed_from") or 0)
    print(f"run {run_dir}: {metrics['status']}, {steps} env steps, {metrics['n_envs']} envs, "
          f"{total:.1f} s")
    print("| part | s | share | µs per env step |\n|---|---:|---:|---:|")
    for key, label in PARTS:
        s = timing[key]
        share = 100 * s / total if total else 0.0
        print(f"| {label} | {s:.1f} | {share:.1f} % | {1e6 * s / max(steps, 1):.0f} |")
    print(f"| total | {total:.1f} | 100 % | {1e6 * total / max(steps, 1):.0f} |")
    policy = timing.get("worker_policy_s", 0.0)
    if policy:
        print(f"(of the env stepping, {policy:.1f} s was the policy acting in the env processes)")
    history = EvalHistory.load(run_dir / EVAL_LOG / EVALUATIONS)
    if history.timesteps:
        n = len(history.timesteps)
        per = timing["evaluation_s"] / n
        print(f"\n{n} evaluations of {len(history.results[0])} episode(s), {per:.2f} s each; "
              "curve (steps: mean return, last-half mean speed m/s; * = new best):")
        best = float("-inf")
        for t, r, v in zip(history.timesteps, history.results, history.last_half_speed,
                           strict=True):
            mean = sum(r) / len(r)
            mark = "*" if mean > best else " "
            best = max(best, mean)
            print(f"  {t:>8} {mean:10.1f} {sum(v) / len(v):7.3f} {mark}")


def main() -> None:
    """Train (or read a run folder) and print the breakdown."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="configs/ring_wave.yaml")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--set", dest="sets", action="append", default=[])
    parser.add_argument("--out", type=Path, default=Path("runs/train_breakdown"))
    parser.add_argument("--run", type=Path, help="print the breakdown of this run folder")
    args = parser.parse_args()
    if args.run is not None:
        print_breakdown(args.run)
        return
    from flowrun.loading.loader import load_config
    from flowrun.training.trainer import train

    cfg = load_config(args.config, [*args.sets, f"sim.seed={args.seed}",
                                    f"train.seed={args.seed}"])
    print(f"load before: {os.getloadavg()[0]:.2f} (1-min average)", flush=True)
    result = train(cfg, out=args.out, argv=["bench/train_breakdown.py"])
    print(f"load after: {os.getloadavg()[0]:.2f}")
    print_breakdown(result.run_dir)


if __name__ == "__main__":
    main()
