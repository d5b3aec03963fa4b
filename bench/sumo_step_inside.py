"""How long SUMO's own step takes alone vs inside flowrun's loop (same process, same ring).

``(b) - (a)`` in ``bench/ring.py`` is not all Python work: ``simulationStep`` itself can run
slower between flowrun's per-step work (colder caches) than in a tight loop, and with every car
commanded by ``slowDown``. Each repetition times (a) the floor of ``bench/ring.py``, then
(b) ``flowrun baseline --no-record``'s loop with only ``SimulationKernel.simulation_step``
(``simulationStep`` plus SUMO's time and collision/teleport counters) timed.

Run: ``.venv/bin/python bench/sumo_step_inside.py [--reps 5]``
"""

from __future__ import annotations

import argparse
import statistics
import time

from ring import Ring, config, time_floor

from flowrun.envs.factory import make_env
from flowrun.experiment.runner import Experiment
from flowrun.kernel.simulation import SimulationKernel


def sumo_step_inside(ring: Ring) -> float:
    """µs per ``SimulationKernel.simulation_step`` during ``Experiment.run`` (after warm-up)."""
    spent = {"s": 0.0, "n": 0}
    plain = SimulationKernel.simulation_step

    def timed(self: SimulationKernel) -> None:
        t0 = time.perf_counter()
        plain(self)
        if self.step_count > ring.warmup:
            spent["s"] += time.perf_counter() - t0
            spent["n"] += 1

    SimulationKernel.simulation_step = timed  # type: ignore[method-assign]
    env = make_env(config("sugiyama", ring))
    try:
        Experiment(env).run(1, ring.warmup + ring.steps, seed=0)
    finally:
        env.close()
        SimulationKernel.simulation_step = plain  # type: ignore[method-assign]
    return spent["s"] / spent["n"] * 1e6


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--reps", type=int, default=5)
    args = p.parse_args()
    ring = Ring("small", 1, 3000, 300)
    alone, inside = [], []
    for _ in range(args.reps):
        alone.append(time_floor(ring))
        inside.append(sumo_step_inside(ring))
    a, b = statistics.median(alone), statistics.median(inside)
    for label, values, med in (("alone (the floor)", alone, a), ("inside flowrun", inside, b)):
        print(f"SUMO step {label:18} {med:6.1f} µs (range {min(values):.1f}-{max(values):.1f})")
    print(f"inside / alone = {b / a:.2f} (median of {args.reps} repetitions)")


if __name__ == "__main__":
    main()
