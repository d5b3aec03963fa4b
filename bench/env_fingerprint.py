"""A fingerprint of an environment's behaviour: sha256 of its observations and rewards under
seeded random actions. Equal fingerprints at two commits mean the env (and the simulation
under it) did not change for that config.

Run: ``.venv/bin/python bench/env_fingerprint.py [CONFIG] [--seeds 0 1] [--steps 2300]``.
Another commit's code with this script:
``git worktree add /tmp/old REV && PYTHONPATH=/tmp/old .venv/bin/python bench/env_fingerprint.py``.
"""

from __future__ import annotations

import argparse
import hashlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config

CONFIG = Path(__file__).resolve().parent.parent / "configs" / "ring_wave.yaml"


def random_rollout(env: Any, seed: int, steps: int) -> Iterator[tuple[Any, float | None, bool]]:
    """Reset ``env`` with ``seed``, then take at most ``steps`` actions drawn uniformly in
    [-1, 1] by a generator seeded with ``seed``, up to the episode's end.

    Yields ``(observation, reward, last)`` after the reset (reward ``None``) and after every
    step; ``last`` is true where no step follows. The env is not closed.
    """
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    yield obs, None, steps == 0
    for taken in range(1, steps + 1):
        action = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        obs, reward, terminated, truncated, _ = env.step(action)
        yield obs, reward, bool(terminated or truncated or taken == steps)
        if terminated or truncated:
            return


def obs_bytes(obs: Any) -> Iterator[bytes]:
    """An observation's float64 bytes, part by part where it is a tuple."""
    for part in obs if isinstance(obs, tuple) else (obs,):
        yield np.asarray(part, np.float64).tobytes()


def fingerprint(config: Path, seeds: list[int], steps: int) -> tuple[str, int]:
    """The sha256 (hex) of every observation and reward, and the steps taken in all."""
    env = make_env(load_config(config))
    digest, taken = hashlib.sha256(), 0
    try:
        for seed in seeds:
            for obs, reward, _ in random_rollout(env, seed, steps):
                for chunk in obs_bytes(obs):
                    digest.update(chunk)
                if reward is not None:
                    digest.update(np.float64(reward).tobytes())
                    taken += 1
    finally:
        env.close()
    return digest.hexdigest(), taken


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("config", nargs="?", type=Path, default=CONFIG)
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    p.add_argument("--steps", type=int, default=2300, help="env steps per seed at most")
    args = p.parse_args()
    digest, taken = fingerprint(args.config, args.seeds, args.steps)
    print(f"{args.config.name}: seeds {args.seeds}, {taken} env steps: sha256 {digest[:16]}")


if __name__ == "__main__":
    main()
