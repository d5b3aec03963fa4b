"""Step cost of the grid benchmarks (grid0 3x3, grid1 5x5) against SUMO alone, in one run.

Usage: ``.venv/bin/python bench/grid.py [steps] [repeats]`` (400 and 9 by default).

For each network: a first env run (not timed) logs what the env tells SUMO (signal states
per step, the modes of entering cars; ``bench/grid_steps.py``); SUMO alone replaying that log
must hold the same number of cars at every step (checked: "same traffic"). Then the env
(``TrafficLightGridBenchmarkEnv``, seeded random switch actions, one episode of ``steps``
steps, no reset inside the timing) and the replay take turns ``repeats`` times, each from the
same reset. Times are this process's CPU time (``time.process_time``: time spent waiting
for a core on a busy machine is not counted), µs per step: the median of the repeats (and
"min": the ratio of the fastest runs, the least disturbed by other work; single runs of a
few hundred ms on a shared 2-core machine scatter by +-30 %).

Before this bench replayed the env's traffic, SUMO alone ran its own programs without the
signal file (other traffic: grid0 65 cars on average against the env's 62) and the env's
timing included the reset at the end of the episode (grid0: ~9 ms, ~23 µs per step).
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from grid_steps import GRIDS, actions, make_grid_env, record, replay  # bench/, beside this file


def env_us(name: str, steps: int) -> float:
    """CPU µs per env step over one episode of ``steps`` steps."""
    env = make_grid_env(name, steps)
    todo = actions(env, steps)
    t0 = time.process_time()
    for action in todo:
        env.step(action)
    elapsed = time.process_time() - t0
    env.close()
    return elapsed / steps * 1e6


def raw_us(name: str, steps: int, log: object) -> float:
    """CPU µs per step of SUMO alone replaying the env's commands."""
    env = make_grid_env(name, steps)
    assert env.k.process is not None
    api = env.k.process.api
    t0 = time.process_time()
    replay(api, log, steps)  # type: ignore[arg-type]
    elapsed = time.process_time() - t0
    env.close()
    return elapsed / steps * 1e6


def main() -> None:
    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 400
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 9
    print(f"load before: {os.getloadavg()[0]:.2f}")
    for name in GRIDS:
        log = record(name, steps)
        env = make_grid_env(name, steps)
        assert env.k.process is not None
        same = replay(env.k.process.api, log, steps, count=True) == log.counts
        env.close()
        runs = [(env_us(name, steps), raw_us(name, steps, log)) for _ in range(repeats)]
        e = statistics.median(r[0] for r in runs)
        r = statistics.median(r[1] for r in runs)
        fastest = min(r[0] for r in runs) / min(r[1] for r in runs)
        cars = sum(log.counts) / steps
        print(f"{name}: env {e:6.0f} us/step  SUMO alone {r:6.0f} us/step  ratio {e / r:5.2f}  "
              f"(min {fastest:.2f}; runs {', '.join(f'{a / b:.2f}' for a, b in runs)})  "
              f"mean cars {cars:.0f}  same traffic: {'yes' if same else 'NO'}")  # fmt: skip
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
