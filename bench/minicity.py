"""What MinicityRouter costs per simulation step on Flow's mini city (100 cars).

Run: ``.venv/bin/python bench/minicity.py [--steps 1500] [--seed 0] [--lookahead M]``. Runs
``configs/minicity.yaml`` for ``--steps`` simulation steps (no recording) and prints, in
microseconds per simulation step (medians over the steps): the whole step of the env,
SUMO's own ``simulationStep``, and the routers (``GroupRouters.step``, which decide and set
the new routes), plus how many cars were rerouted per step on average.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from pathlib import Path
from typing import Any

from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config

CONFIG = Path(__file__).resolve().parent.parent / "configs" / "minicity.yaml"


class Timed:
    """Wraps a callable and keeps the duration of each call, s."""

    def __init__(self, fn: Any) -> None:
        self.fn = fn
        self.times: list[float] = []

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        out = self.fn(*args, **kwargs)
        self.times.append(time.perf_counter() - t0)
        return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1500, help="simulation steps")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--lookahead", type=float, default=None, help="router lookahead, m")
    args = parser.parse_args()
    sets = ["env.sims_per_step=1", f"env.horizon={args.steps}"]
    if args.lookahead is not None:
        sets += [f"vehicles.{i}.routing_controller.lookahead={args.lookahead}" for i in (0, 1)]
    cfg = load_config(CONFIG, sets)
    env = make_env(cfg)
    try:
        env.reset(seed=args.seed)
        vk = env.k.vehicle
        routers = env.k.group_routers
        router_step = Timed(routers.step)
        routers.step = router_step
        sim = env.k.simulation  # the kernel steps SUMO through a frozen table of calls
        sumo_step = Timed(sim._fast.sim_step)
        sim._fast = dataclasses.replace(sim._fast, sim_step=sumo_step)
        rerouted = Timed(vk.reroute_now)
        vk.reroute_now = rerouted  # type: ignore[method-assign]
        counts: list[int] = []
        original = rerouted.fn

        def counted(rows: Any, routes: Any) -> Any:
            counts.append(len(rows))
            return original(rows, routes)

        rerouted.fn = counted
        steps: list[float] = []
        for _ in range(args.steps):
            t0 = time.perf_counter()
            _, _, terminated, _, _ = env.step(None)
            steps.append(time.perf_counter() - t0)
            if terminated:
                break
    finally:
        env.close()
    us = 1e6
    print(f"minicity, {len(steps)} simulation steps, {len(vk.get_ids())} cars, seed {args.seed}")
    print(f"env step (median)      {statistics.median(steps) * us:8.1f} us")
    print(f"SUMO simulationStep    {statistics.median(sumo_step.times) * us:8.1f} us")
    print(f"routers (median)       {statistics.median(router_step.times) * us:8.1f} us")
    print(f"routers (mean)         {statistics.fmean(router_step.times) * us:8.1f} us")
    print(f"cars rerouted per step {sum(counts) / max(len(router_step.times), 1):8.2f}")


if __name__ == "__main__":
    main()
