"""Run Flow's grid0 or grid1 for N steps: the env, or SUMO alone on the same files.

For instruction counts (``bench/grid_instructions.sh`` runs this under callgrind twice and
takes the difference per step). ``env``: ``TrafficLightGridBenchmarkEnv`` with seeded random
switch actions, one episode as long as the run, recording off. ``raw``: the same network,
routes (300 veh/h per entering edge) and signal programs after the env's reset, stepped by
``simulationStep`` alone (SUMO runs its own programs).

Usage: ``.venv/bin/python bench/grid_steps.py {env|raw} {grid0|grid1} STEPS``.
"""

from __future__ import annotations

import sys

import numpy as np

from flowrun.envs.factory import make_env
from flowrun.envs.grid_defaults import grid_config

GRIDS = {"grid0": (3, 3), "grid1": (5, 5)}


def run_grid(mode: str, name: str, steps: int) -> None:
    """``steps`` steps of grid ``name``: ``raw`` SUMO alone, otherwise the env."""
    config = grid_config(*GRIDS[name])
    config.env.horizon = max(config.env.horizon, steps)  # one episode (Flow's 400 < 600)
    env = make_env(config)
    env.reset(seed=0)
    if mode == "raw":
        assert env.k.process is not None
        step = env.k.process.api.simulationStep
        for _ in range(steps):
            step()
    else:
        rng = np.random.default_rng(0)
        n_actions = env.action_space.shape[0]  # type: ignore[index]
        for _ in range(steps):
            env.step(rng.uniform(-1, 1, n_actions).astype(np.float32))
    env.close()


def main() -> None:
    """Command line: mode, grid name, steps."""
    run_grid(sys.argv[1], sys.argv[2], int(sys.argv[3]))


if __name__ == "__main__":
    main()
