"""A fingerprint of the traffic-light grid envs' behaviour under seeded random switch actions.

For grid0 (3x3) and grid1 (5x5) and each grid env (the benchmark env training and
evaluating, the PO env, the fully observed env with its re-insertion), hashes (sha256) every
observation and reward together with the simulation under them: the cars' ids, speeds, lane
positions and edges, and every light's state string. Equal fingerprints before and after a
change mean the change altered nothing the envs show or do.

Run: ``.venv/bin/python bench/grid_fingerprint.py [--steps 300] [--seed 0]``.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

from flowrun.envs.defaults import grid_config
from flowrun.envs.factory import make_env

sys.path.insert(0, str(Path(__file__).resolve().parent))
from env_fingerprint import obs_bytes, random_rollout  # bench/, beside this file

#: (label, rows, cols, env class, evaluate)
CASES: tuple[tuple[str, int, int, str, bool], ...] = (
    ("grid0 benchmark", 3, 3, "TrafficLightGridBenchmarkEnv", False),
    ("grid0 benchmark eval", 3, 3, "TrafficLightGridBenchmarkEnv", True),
    ("grid0 PO", 3, 3, "TrafficLightGridPOEnv", False),
    ("grid0 full", 3, 3, "TrafficLightGridEnv", False),
    ("grid1 benchmark", 5, 5, "TrafficLightGridBenchmarkEnv", False),
)


def fingerprint(rows: int, cols: int, env_class: str, evaluate: bool, steps: int,
                seed: int) -> tuple[str, int]:  # fmt: skip
    """The sha256 (hex) of observations, rewards and simulation state, and the steps taken.

    Before every step: the observation, then the simulation state; after it: the reward.
    """
    config = grid_config(rows, cols, env_class)
    config.env.evaluate = evaluate
    env = make_env(config)
    digest, taken = hashlib.sha256(), 0
    try:
        for obs, reward, last in random_rollout(env, seed, steps):
            if reward is not None:
                digest.update(np.float64(reward).tobytes())
                taken += 1
            if last:
                break
            for chunk in obs_bytes(obs):
                digest.update(chunk)
            vk, tk = env.k.vehicle, env.k.traffic_light
            digest.update("|".join(vk.get_ids()).encode())
            digest.update("|".join(vk.edges).encode())
            digest.update(np.asarray(vk.speed, np.float64).tobytes())
            digest.update(np.asarray(vk.lane_pos, np.float64).tobytes())
            digest.update("|".join(tk.get_state(t) for t in tk.get_ids()).encode())
    finally:
        env.close()
    return digest.hexdigest(), taken


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=300, help="env steps per case at most")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args()
    for label, rows, cols, env_class, evaluate in CASES:
        digest, taken = fingerprint(rows, cols, env_class, evaluate, args.steps, args.seed)
        print(f"{label:22s} {taken} steps: sha256 {digest[:16]}")


if __name__ == "__main__":
    main()
