"""What one rendered frame costs next to the simulation steps of the same run.

Run: ``.venv/bin/python bench/render_frame.py [--steps 200] [--frames 30] [config names ...]``.

For each config: the env (``render_mode="rgb_array"``) is reset and stepped ``--steps`` times
(no action: the configs' own controllers drive); the mean wall time of one *simulation* step is
the env steps' time divided by the simulation steps they took. Then ``env.render()`` is called
``--frames`` times (the first call, which reads the network file and draws the road, is timed
apart). Printed: µs per simulation step, µs per frame (median), and the frame in simulation
steps: the target is at most 10.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
DEFAULT = ("sugiyama", "merge", "figure_eight", "grid0", "bottleneck", "minicity")


def bench(name: str, steps: int, frames: int, overrides: list[str]) -> tuple[float, float, float]:
    """(µs per simulation step, µs of the first frame, median µs per frame)."""
    cfg = load_config(CONFIGS / f"{name}.yaml", overrides)
    env = make_env(cfg, render_mode="rgb_array")
    try:
        env.reset(seed=0)
        sims = cfg.env.sims_per_step
        start = time.perf_counter()
        for _ in range(steps):
            env.step(None)
        step_us = (time.perf_counter() - start) / (steps * sims) * 1e6
        t0 = time.perf_counter()
        env.render()
        first_us = (time.perf_counter() - t0) * 1e6
        times = []
        for _ in range(frames):
            env.step(None)
            t0 = time.perf_counter()
            env.render()
            times.append((time.perf_counter() - t0) * 1e6)
        return step_us, first_us, statistics.median(times)
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*", default=list(DEFAULT))
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parser.parse_args()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"load average {load:.2f}")
    print(f"{'config':<14} {'µs/sim step':>12} {'first frame µs':>15} {'µs/frame':>10} "
          f"{'frame in steps':>15}")  # fmt: skip
    for name in args.configs:
        step_us, first_us, frame_us = bench(name, args.steps, args.frames, args.overrides)
        print(f"{name:<14} {step_us:12.0f} {first_us:15.0f} {frame_us:10.0f} "
              f"{frame_us / step_us:15.1f}")  # fmt: skip


if __name__ == "__main__":
    main()
