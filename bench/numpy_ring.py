"""Throughput of the numpy ring backend (``sim.backend: numpy``), and where SB3 takes over.

For each number of rings B, env-steps per second (B rings x vector steps / wall time) of:

- ``rings``: the backend alone (``RingVecEnv.step``: physics, noise, observations, rewards,
  automatic resets with their warm-up);
- ``+wrappers``: inside ``VecMonitor`` and ``VecNormalize`` (what ``flowrun train`` wraps);
- ``+predict``: plus SB3's ``policy.predict`` of a 64x64 MLP on the B observations per step
  (the per-step work of SB3's rollout collection, without its buffer);
- ``learn``: SB3 TRPO ``learn`` itself (collection + buffer + updates, ``n_steps`` per ring
  chosen so a batch holds ~6,000 steps as in configs/ring_wave.yaml).

Wall-clock numbers on a shared machine: the 1-minute load average is printed before and after.

    .venv/bin/python bench/numpy_ring.py [--config configs/ring_wave_numpy.yaml]
        [--rings 1 16 64 256 1024] [--steps 2000] [--learn 60000]

Load-proof: instructions per vector step of B rings, counted by valgrind for two step counts
(start-up cancels out in the difference), e.g. for B = 256:

    for n in 200 600; do OPENBLAS_NUM_THREADS=1 PYTHONHASHSEED=0 setarch "$(uname -m)" -R \
      valgrind --tool=callgrind --callgrind-out-file=/dev/null .venv/bin/python \
      bench/numpy_ring.py --rings 256 --count $n 2>&1 | grep Collected; done
    # (I_600 - I_200) / 400 instructions per vector step; / 256 per env step
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch
from sb3_contrib import TRPO
from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

from flowrun.fastring.plan import ring_plan
from flowrun.fastring.vec_env import RingVecEnv
from flowrun.loading.loader import load_config


def rate(step: object, rings: int, steps: int) -> str:
    """Env-steps per second of ``steps`` calls of ``step()`` on ``rings`` rings: per second of
    wall time, and per second of this process's CPU time (what an idle core would give; on a
    loaded machine the wall-clock rate falls with the share of a core the process gets)."""
    start, cpu = time.perf_counter(), time.process_time()
    for _ in range(steps):
        step()  # type: ignore[operator]
    wall, used = time.perf_counter() - start, time.process_time() - cpu
    return f"{rings * steps / wall:,.0f} ({rings * steps / used:,.0f})"


def main() -> None:
    """Print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", type=Path, default=Path("configs/ring_wave_numpy.yaml"))
    parser.add_argument("--rings", type=int, nargs="+", default=[1, 16, 64, 256, 1024])
    parser.add_argument("--steps", type=int, default=2000, help="vector steps per measure")
    parser.add_argument("--learn", type=int, default=60000, help="env steps of TRPO learn")
    parser.add_argument(
        "--count",
        type=int,
        default=0,
        help="only reset and run this many vector steps of --rings (valgrind)",
    )
    args = parser.parse_args()
    torch.set_num_threads(1)
    plan = ring_plan(load_config(args.config))
    if args.count:
        venv = RingVecEnv(plan, args.rings[0])
        venv.seed(0)
        venv.reset()
        zeros = np.zeros((args.rings[0], plan.rl_rows.size), dtype=np.float32)
        for _ in range(args.count):
            venv.step(zeros)
        return
    print(
        f"load before: {os.getloadavg()[0]:.2f}; {args.config}: {plan.num_cars} cars, "
        f"{plan.rl_rows.size} RL, horizon {plan.horizon} + warm-up {plan.warmup}"
    )
    print("env-steps/s of wall time (and per CPU-second of this process)")
    print("| rings | reset s | rings | +wrappers | +predict | learn (TRPO) |")
    print("|---:|---:|---:|---:|---:|---:|")
    for b in args.rings:
        steps = max(50, min(args.steps, args.steps * 64 // b))
        venv = RingVecEnv(plan, b)
        venv.seed(0)
        start = time.perf_counter()
        venv.reset()
        reset_s = time.perf_counter() - start
        actions = np.zeros((b, plan.rl_rows.size), dtype=np.float32)
        raw = rate(lambda v=venv, a=actions: v.step(a), b, steps)
        wrapped = VecNormalize(VecMonitor(venv), gamma=0.999)
        wrapped.reset()
        wrap = rate(lambda v=wrapped, a=actions: v.step(a), b, steps)
        n_steps = max(8, 6000 // b)
        model = TRPO("MlpPolicy", wrapped, policy_kwargs={"net_arch": [64, 64]}, device="cpu",
                     n_steps=n_steps, batch_size=n_steps * b // 10, seed=0)  # fmt: skip
        last: list[Any] = [wrapped.reset()]

        def predict(m: TRPO = model, v: VecNormalize = wrapped, last: list[Any] = last) -> None:
            action, _ = m.predict(last[0], deterministic=False)
            last[0] = v.step(action)[0]

        pred = rate(predict, b, steps)
        learn = "-"
        if args.learn:
            start, cpu = time.perf_counter(), time.process_time()
            model.learn(args.learn)
            wall, used = time.perf_counter() - start, time.process_time() - cpu
            learn = f"{model.num_timesteps / wall:,.0f} ({model.num_timesteps / used:,.0f})"
        print(f"| {b} | {reset_s:.2f} | {raw} | {wrap} | {pred} | {learn} |", flush=True)
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
