"""Training throughput: environment steps per second with 1 and 2 ``SubprocVecEnv`` envs.

Learning updates are included (``n_steps`` per env, then an update), so the number is what
``flowrun train`` achieves, not the raw simulator speed. Measured for PPO and for the config's
own algorithm (with its hyper-parameters, ``n_steps`` capped so that an update happens), plus
the raw single-env step rate (no learning) for comparison. No evaluation runs are included.

    .venv/bin/python bench/train_throughput.py [--config configs/ring_wave.yaml] [--steps 12000]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from flowrun.config.loader import load_config
from flowrun.config.model import ExperimentConfig
from flowrun.envs.factory import make_env
from flowrun.training.algorithms import algorithm_class, build_hyperparams
from flowrun.training.vecenv import make_vec_env


def raw_env_rate(cfg: ExperimentConfig, steps: int) -> float:
    """Env steps/s of one env in this process, zero action, resets included."""
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        action = np.zeros(env.action_space.shape, dtype=np.float32)
        start = time.perf_counter()
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                env.reset()
        return steps / (time.perf_counter() - start)
    finally:
        env.close()


def train_rate(cfg: ExperimentConfig, algorithm: str, n_envs: int, steps: int) -> float:
    """Env steps/s of an on-policy algorithm learning on ``n_envs`` subprocesses.

    The config's hyper-parameters are used when it trains with ``algorithm``, SB3's otherwise.
    """
    import torch

    torch.set_num_threads(1)  # as flowrun train does
    assert cfg.train is not None
    tc = cfg.train
    venv = make_vec_env(cfg, n_envs, seed=0)
    try:
        own = tc.hyperparams if tc.algorithm == algorithm else {}
        hyper = build_hyperparams(algorithm, own, 1)
        hyper["n_steps"] = min(int(hyper.get("n_steps", 2048)), steps // n_envs)
        hyper["batch_size"] = min(int(hyper.get("batch_size", 64)), hyper["n_steps"] * n_envs)
        model = algorithm_class(algorithm)(
            "MlpPolicy", venv, policy_kwargs=dict(tc.policy_kwargs) or None, seed=0,
            device="cpu", **hyper,
        )
        start = time.perf_counter()
        model.learn(steps)
        return model.num_timesteps / (time.perf_counter() - start)
    finally:
        venv.close()


def main() -> None:
    """Print the throughput table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="configs/ring_wave.yaml")
    parser.add_argument("--steps", type=int, default=12_000, help="env steps per measurement")
    args = parser.parse_args()
    cfg = load_config(args.config)
    print(f"config {args.config}: horizon {cfg.env.horizon}, warm-up {cfg.env.warmup_steps}")
    raw = raw_env_rate(cfg, args.steps)
    print(f"raw env (1 env in this process, no learning, warm-up resets incl.): "
          f"{raw:8.0f} env steps/s")
    assert cfg.train is not None
    for algorithm in dict.fromkeys(("PPO", cfg.train.algorithm)):
        for n in (1, 2):
            rate = train_rate(cfg, algorithm, n, args.steps)
            print(f"{algorithm}, {n} SubprocVecEnv env(s), updates incl.: "
                  f"{rate:8.0f} env steps/s")


if __name__ == "__main__":
    main()
