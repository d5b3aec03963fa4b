"""Training throughput against the env's own speed, per config, in one run.

For each config: the env's own rate (one env in this process, no learning, zero actions,
resets included), then the rate of ``flowrun.training.train`` (exactly what ``flowrun train``
runs, start-up and the closing evaluation left out) with the config's ``train:`` section and
``train.n_envs`` envs, and the ratio of the two. The target on a machine of ``C`` cores is a
ratio of at least ``0.6 * C``. Periodic evaluation is off unless ``--eval`` (it runs on one env
in the driver process); checkpoints are off.

    .venv/bin/python bench/train_throughput.py [CONFIG ...] [--steps 30000] [--eval]
        [--set train.n_envs=4]

Without CONFIG: the four benchmarks figureeight0, merge0, grid0 and bottleneck0. Each part of
the training's wall clock (env stepping, policy inference, updates) is printed after it.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config
from flowrun.training.trainer import train

BENCHMARKS = tuple(
    f"configs/benchmarks/{name}.yaml"
    for name in ("figureeight0", "merge0", "grid0", "bottleneck0")
)


def env_rate(cfg: ExperimentConfig, steps: int) -> float:
    """Env steps/s of one env in this process, zero action, resets included."""
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        space = env.action_space
        assert space.shape is not None and space.dtype is not None  # Box and Discrete have both
        action = np.zeros(space.shape, dtype=space.dtype)
        start = time.perf_counter()
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                env.reset()
        return steps / (time.perf_counter() - start)
    finally:
        env.close()


def train_rate(config: str, sets: list[str], steps: int, evaluate: bool) -> tuple[float, str]:
    """Env steps/s of ``train`` on the config (start-up excluded), and its time breakdown."""
    overrides = [*sets, f"train.total_timesteps={steps}", "train.checkpoint_freq=100000000"]
    if not evaluate:
        overrides.append("train.eval_freq=0")
    cfg = load_config(config, overrides)
    with tempfile.TemporaryDirectory() as out:
        result = train(cfg, out=Path(out), argv=["bench/train_throughput.py"])
    timing = result.timing
    assert timing is not None and cfg.train is not None
    done = max(result.timesteps, 1)
    parts = ", ".join(
        f"{label} {1e6 * seconds / done:.0f}"
        for label, seconds in (
            ("env wait", timing.env_wait),
            ("of it policy in the env processes", getattr(timing, "worker_policy", 0.0)),
            ("inference+loop", timing.inference),
            ("updates", timing.update), ("evaluation", timing.evaluation),
        )
    )
    detail = f"{cfg.train.n_envs} envs; µs per env step: {parts}"
    return result.steps_per_second, detail


@dataclass
class Throughput:
    """One config's env alone against its training loop.

    Attributes:
        name: the config's name.
        alone: env steps/s of one env alone.
        training: env steps/s of the training loop.
        detail: the training's envs and where its time went.
    """

    name: str
    alone: float
    training: float
    detail: str

    @property
    def ratio(self) -> float:
        """Training over one env alone."""
        return self.training / self.alone


def target(cores: int) -> float:
    """The lowest ratio that meets the target on ``cores`` cores: 60 % of them."""
    return 0.6 * cores


def measure(config: str, sets: list[str], steps: int, env_steps: int,
            evaluate: bool = False) -> Throughput:  # fmt: skip
    """One env alone for ``env_steps`` steps, then ``train`` for ``steps`` steps."""
    cfg = load_config(config, sets)
    alone = env_rate(cfg, env_steps)
    rate, detail = train_rate(config, sets, steps, evaluate)
    return Throughput(cfg.name, alone, rate, detail)


def main() -> None:
    """Print the table: env rate, training rate, ratio, target."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*", default=list(BENCHMARKS))
    parser.add_argument("--steps", type=int, default=30_000, help="training env steps")
    parser.add_argument("--env-steps", type=int, default=6_000, help="env-alone steps")
    parser.add_argument("--eval", action="store_true", help="keep the periodic evaluation")
    parser.add_argument("--set", dest="sets", action="append", default=[])
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    print(f"{cores} cores; load {os.getloadavg()[0]:.2f} (1-min average); target ratio "
          f">= {target(cores):.1f}", flush=True)
    rows = []
    for config in args.configs:
        t = measure(config, args.sets, args.steps, args.env_steps, args.eval)
        rows.append(t)
        print(f"{t.name}: env alone {t.alone:.0f} steps/s, training {t.training:.0f} steps/s, "
              f"ratio {t.ratio:.2f} ({t.detail}); load {os.getloadavg()[0]:.2f}", flush=True)
    print("\n| config | env alone, steps/s | training, steps/s | ratio | target |")
    print("|---|---:|---:|---:|---:|")
    for t in rows:
        mark = "yes" if t.ratio >= target(cores) else "no"
        print(f"| {t.name} | {t.alone:.0f} | {t.training:.0f} | {t.ratio:.2f} | {mark} |")


if __name__ == "__main__":
    main()
