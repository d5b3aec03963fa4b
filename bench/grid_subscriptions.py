"""Per-car reads on Flow's grids: libsumo getters against vehicle subscriptions, in one run.

Reads every car's speed, lane id and lane position after each step, as the open-network
kernel does, either with plain getters (one call per car and value) or with libsumo's
vehicle subscriptions (each car subscribed once when it enters; all results fetched with
``getAllSubscriptionResults``), and prints µs per step of SUMO's step and of the reading.
Subscriptions make SUMO's step dearer (it collects the results every step) and the Python
dicts they come back in cost more to read than the getters at these sizes.

Usage: ``.venv/bin/python bench/grid_subscriptions.py [steps]`` (600 by default; 200 steps
first fill the network, untimed).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from grid_steps import make_grid_env  # bench/, beside this file

#: libsumo's variable ids: speed, lane id, lane position
VARS = (0x40, 0x51, 0x56)


def run(name: str, steps: int, mode: str) -> tuple[float, float, float]:
    """µs per step of SUMO's step and of the reads (``none``, ``get`` or ``sub``), mean cars."""
    env = make_grid_env(name, 200 + steps)
    assert env.k.process is not None
    api: Any = env.k.process.api
    raw = api._libsumo
    for _ in range(200):
        api.simulationStep()
    ids = list(api.vehicle.getIDList())
    if mode == "sub":
        for vid in ids:
            raw.vehicle_subscribe(vid, VARS)
    speed, lane, lane_pos = raw.vehicle_getSpeed, raw.vehicle_getLaneID, raw.vehicle_getLanePosition
    step_s = read_s = 0.0
    cars = 0
    for _ in range(steps):
        t0 = time.process_time()
        raw.simulation_step(0.0)
        t1 = time.process_time()
        departed = list(raw.simulation_getDepartedIDList())
        arrived = set(raw.simulation_getArrivedIDList())
        ids = [v for v in ids if v not in arrived] + departed
        t2 = time.process_time()
        if mode == "sub":
            for vid in departed:
                raw.vehicle_subscribe(vid, VARS)
            results = raw.vehicle_getAllSubscriptionResults()
            rows = [results[v] for v in ids]
            np.fromiter((r[0x40] for r in rows), np.float64, len(ids))
            [r[0x51] for r in rows]
            np.fromiter((r[0x56] for r in rows), np.float64, len(ids))
        elif mode == "get":
            np.fromiter(map(speed, ids), np.float64, len(ids))
            list(map(lane, ids))
            np.fromiter(map(lane_pos, ids), np.float64, len(ids))
        t3 = time.process_time()
        step_s += t1 - t0
        read_s += t3 - t2
        cars += len(ids)
    env.close()
    return step_s / steps * 1e6, read_s / steps * 1e6, cars / steps


def main() -> None:
    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 600
    print(f"load: {os.getloadavg()[0]:.2f}")
    for name in ("grid0", "grid1"):
        for mode in ("none", "get", "sub"):
            step_us, read_us, cars = run(name, steps, mode)
            print(f"{name} {mode:4s}: SUMO step {step_us:6.0f} us, reads {read_us:5.0f} us "
                  f"per step, {cars:.0f} cars")  # fmt: skip


if __name__ == "__main__":
    main()
