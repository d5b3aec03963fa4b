"""The bottleneck's capacity drop: outflow against inflow, all human drivers.

Run: ``.venv/bin/python bench/capacity_drop.py`` (a few minutes; ``--help`` for the grid).
Each inflow runs ``configs/bottleneck.yaml`` (Flow's bottleneck, scaling 1, SUMO's drivers
with Flow's lane-change mode ``sumo_default``) with ``--seeds`` seeds for ``--seconds``
simulated seconds, and measures the outflow (cars leaving the end of edge ``5``) over the
last ``--window`` seconds. Below capacity the outflow follows the inflow; above it the
zipper merges break down, queues grow upstream and the outflow falls (Flow's capacity drop).
Prints a Markdown table: inflow, mean outflow, std over seeds, cars still waiting to enter.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config, override_config

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bottleneck_sumo import print_table, table_options  # bench/, beside this file

CONFIG = Path(__file__).resolve().parent.parent / "configs" / "bottleneck.yaml"


def measure_outflow(
    inflow: float,
    seed: int,
    seconds: float,
    window: float,
    overrides: tuple[str, ...] = (),
    config: Path = CONFIG,
) -> tuple[float, int]:
    """Outflow (veh/h) over the last ``window`` s of a ``seconds``-long all-human run with
    ``inflow`` veh/h entering edge ``1``, and the cars left waiting to enter at the end."""
    cfg = load_config(config, [f"network.inflows.0.vehs_per_hour={inflow}", *overrides])
    steps = round(seconds / cfg.sim.sim_step)
    env = make_env(override_config(cfg, [f"env.horizon={steps}", "env.sims_per_step=1"]))
    try:
        env.reset(seed=seed)
        vk = env.k.vehicle
        arrived, counted = 0, round(window / cfg.sim.sim_step)
        for step in range(steps):
            env.step(None)
            if step >= steps - counted:
                arrived += len(vk.get_arrived_ids())
        return arrived * 3600.0 / window, vk.get_num_not_departed()
    finally:
        env.close()


def main() -> None:
    """Print the outflow-inflow table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    table_options(parser, "800,1200,1600,2000,2400,2800,3200")
    args = parser.parse_args()

    def runs(inflow: float) -> list[tuple[float, int]]:
        return [measure_outflow(inflow, s, args.seconds, args.window, tuple(args.set))
                for s in range(args.seeds)]  # fmt: skip

    print_table(args, "bottleneck (scaling 1)", "waiting to enter", runs, statistics.mean)


if __name__ == "__main__":
    main()
