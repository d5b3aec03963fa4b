"""How fast the benchmarks learn on this machine: training throughput and env step, one table.

Usage::

    .venv/bin/python bench/learning_speed.py [NAME ...] [--quick]

Names: ``configs/benchmarks/NAME.yaml``; figureeight0, merge0, grid0 and bottleneck0 by
default (about 3 min on a 2-core machine, more when other work runs; ``--quick`` about 2
min). Per benchmark, in one run:

- **env step against SUMO alone** (``bench/env_vs_sumo.py``): a first env run logs every write
  the env sends SUMO, SUMO alone replays it on the same traffic (the car count checked equal
  after every step), the two take turns; CPU µs per env step, medians. Target: env ≤ 3× SUMO.
- **training throughput** (``bench/train_throughput.py``): one env alone (steps/s, zero
  actions, resets included), then ``flowrun train``'s loop on the config's own recipe (its
  algorithm and ``n_envs``, periodic evaluation and checkpoints off) for a few of the recipe's
  updates; steps/s with start-up left out. Target: training ≥ 0.6 × cores × one env alone.

The 1-min load average is printed at the start, after each benchmark and at the end; the
table's last column is the load when the benchmark's measurements ended.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from env_vs_sumo import CONFIGS, Comparison, compare  # bench/, beside this file
from train_throughput import Throughput, measure, target

from flowrun.config.model import ExperimentConfig
from flowrun.loading.loader import load_config

BENCHMARKS = ("figureeight0", "merge0", "grid0", "bottleneck0")
#: the env step's target: at most this many times SUMO alone on the same traffic
STEP_TARGET = 3.0


@dataclass(frozen=True)
class Budget:
    """How long each measurement runs.

    Attributes:
        updates: the recipe's updates the training runs for (at least ``min_steps`` steps).
        min_steps: the fewest training env steps.
        env_steps: steps of the env alone.
        steps: env steps per run of the env against SUMO alone.
        repeats: alternating runs of the env and SUMO alone.
    """

    updates: int = 4
    min_steps: int = 30_000
    env_steps: int = 6_000
    steps: int = 600
    repeats: int = 7


QUICK = Budget(updates=2, min_steps=10_000, env_steps=2_000, steps=300, repeats=3)


def update_steps(cfg: ExperimentConfig) -> int:
    """Env steps of one update of the config's ``train:`` recipe: ARS plays ``2 * n_delta``
    candidates of ``n_eval_episodes`` episodes; the others collect ``n_steps`` per env."""
    assert cfg.train is not None, f"{cfg.name} has no train: section"
    h = cfg.train.hyperparams
    if cfg.train.algorithm == "ARS":
        episodes = 2 * int(h.get("n_delta", 8)) * int(h.get("n_eval_episodes", 1))
        return episodes * int(cfg.env.horizon)
    return int(h.get("n_steps", 2048)) * cfg.train.n_envs


@dataclass
class Row:
    """One benchmark's measurements."""

    speed: Throughput
    step: Comparison
    load: float


def measure_benchmark(name: str, budget: Budget) -> Row:
    """The env against SUMO alone, then one env alone against the training loop."""
    config = str(CONFIGS / f"{name}.yaml")
    step = compare(name, budget.steps, budget.repeats)
    steps = max(budget.updates * update_steps(load_config(config)), budget.min_steps)
    speed = measure(config, [], steps, budget.env_steps)
    return Row(speed, step, os.getloadavg()[0])


def table(rows: list[Row], cores: int) -> list[str]:
    """The markdown table of the rows."""
    lines = [
        f"| benchmark | env alone, steps/s | training, steps/s | ratio | ≥ {target(cores):.1f} "
        "| env, µs/step | SUMO alone, µs/step | env/SUMO | ≤ 3× | cars (same) | load |",
        "|---|---:|---:|---:|---|---:|---:|---:|---|---:|---:|",
    ]
    for r in rows:
        s, c = r.speed, r.step
        lines.append(
            f"| {s.name} | {s.alone:,.0f} | {s.training:,.0f} | {s.ratio:.2f} | "
            f"{'yes' if s.ratio >= target(cores) else 'no'} | {c.env:,.0f} | {c.sumo:,.0f} | "
            f"{c.ratio:.2f} | {'yes' if c.ratio <= STEP_TARGET else 'no'} | "
            f"{c.cars:.0f} ({'yes' if c.same else 'NO'}) | {r.load:.2f} |"
        )
    return lines


def main() -> None:
    """Measure every named benchmark and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", default=list(BENCHMARKS), metavar="NAME")
    parser.add_argument("--quick", action="store_true", help="shorter runs (about 2 min)")
    args = parser.parse_args()
    for name in args.names:
        if not (CONFIGS / f"{name}.yaml").exists():
            parser.error(f"no benchmark {name}: no {CONFIGS / f'{name}.yaml'}")
    budget = QUICK if args.quick else Budget()
    cores = os.cpu_count() or 1
    start = time.perf_counter()
    print(f"{cores} cores; load at the start {os.getloadavg()[0]:.2f} (1-min average)", flush=True)
    rows = []
    for name in args.names:
        rows.append(measure_benchmark(name, budget))
        r = rows[-1]
        print(
            f"{name}: training {r.speed.detail}; env/SUMO runs "
            f"{', '.join(f'{a / b:.2f}' for a, b in r.step.runs)} (fastest {r.step.fastest:.2f}),"
            f" {r.step.writes:.1f} writes/step; load {r.load:.2f}",
            flush=True,
        )
    print("", *table(rows, cores), "", sep="\n")
    print(f"load at the end {os.getloadavg()[0]:.2f}; took {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
