"""Step cost of the grid benchmarks (grid0 3x3, grid1 5x5) against SUMO alone, in one run.

Usage: ``.venv/bin/python bench/grid.py [steps]``. Each network runs ``steps`` env steps of
TrafficLightGridBenchmarkEnv (random switch actions) and then the same SUMO files (network,
routes with the 300 veh/h inflows, signal programs) stepped by libsumo alone, with the env's
switches replayed is not attempted: SUMO alone runs its own programs. Prints µs per step.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from flowrun.envs.factory import make_env
from flowrun.envs.grid_defaults import grid_config
from flowrun.kernel.sumo import SumoFiles, SumoProcess


def bench(rows: int, cols: int, steps: int) -> tuple[float, float, int]:
    env = make_env(grid_config(rows, cols))
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    n_actions = env.action_space.shape[0]  # type: ignore[index]
    cars = 0
    t0 = time.perf_counter()
    for _ in range(steps):
        _, _, term, trunc, _ = env.step(rng.uniform(-1, 1, n_actions).astype(np.float32))
        cars += env.k.vehicle.num_vehicles
        if term or trunc:
            env.reset(seed=0)
    env_us = (time.perf_counter() - t0) / steps * 1e6
    net = env.k.net_file
    assert net is not None
    routes = Path(env.work_dir) / f"{net.stem.removesuffix('.net')}.rou.xml"
    files = SumoFiles(net, routes)
    params = env.k.sim_params
    env.k.close()
    proc = SumoProcess(files, params)
    api = proc.start()
    t0 = time.perf_counter()
    for _ in range(steps):
        api.simulationStep()
    raw_us = (time.perf_counter() - t0) / steps * 1e6
    proc.close()
    env.close()
    return env_us, raw_us, cars // steps


def main() -> None:
    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 400
    for name, (rows, cols) in {"grid0": (3, 3), "grid1": (5, 5)}.items():
        env_us, raw_us, cars = bench(rows, cols, steps)
        print(f"{name}: env {env_us:8.0f} us/step  SUMO alone {raw_us:8.0f} us/step  "
              f"ratio {env_us / raw_us:5.2f}  mean cars {cars}")


if __name__ == "__main__":
    main()
