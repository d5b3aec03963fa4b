"""RLlib PPO vs stable-baselines3 PPO on the ring: env steps/s and time to result, one run.

Both train the same env (``configs/rllib_ring.yaml``: WaveAttenuationPOEnv, 22 cars) with the
same number of env processes (SB3: ``SubprocVecEnv`` workers; RLlib: env runners), the same
PPO batch (``--batch`` env steps per update, minibatches of 600, 10 epochs, a 64x64 MLP, same
learning rate and discount), no evaluation and no checkpoints, through flowrun's own entry
points (``flowrun.training.train`` and ``flowrun.training.rllib.train_rllib``). Reported:

* ``steps/s``: env steps per second while training (updates included, start-up excluded);
* ``time to result``: wall time of the whole call, from the config to the trained policy on
  disk (RLlib's includes starting a local Ray and its actors; SB3's its subprocesses).

    /path/to/venv-with-rllib/bin/python bench/rllib_vs_sb3.py [--envs 2] [--steps 24000]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from flowrun.config.model import ExperimentConfig
from flowrun.loading.loader import load_config

CONFIG = Path(__file__).resolve().parent.parent / "configs" / "rllib_ring.yaml"
MINIBATCH, EPOCHS, LR, GAMMA = 600, 10, 5e-4, 0.999


def configs(envs: int, steps: int, batch: int) -> tuple[ExperimentConfig, ExperimentConfig]:
    """The SB3 and the RLlib config of the comparison (same env, same PPO settings)."""
    common = [f"train.total_timesteps={steps}", "train.eval_freq=0", "train.checkpoint_freq=0"]
    sb3 = load_config(CONFIG, [
        *common, "train.backend=sb3", "train.rllib={}", f"train.n_envs={envs}",
        "train.policy_kwargs={net_arch: [64, 64]}",
        f"train.hyperparams={{n_steps: {batch // envs}, batch_size: {MINIBATCH}, "
        f"n_epochs: {EPOCHS}, learning_rate: {LR}, gamma: {GAMMA}}}",
    ])  # fmt: skip
    rllib = load_config(CONFIG, [
        *common, "train.backend=rllib", f"train.num_env_runners={envs}",
        f"train.rllib={{train_batch_size_per_learner: {batch}, minibatch_size: {MINIBATCH}, "
        f"num_epochs: {EPOCHS}, lr: {LR}, gamma: {GAMMA}, "
        "model_config: {fcnet_hiddens: [64, 64]}}",
    ])  # fmt: skip
    return sb3, rllib


def load() -> str:
    """The machine's load averages (1, 5, 15 min)."""
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    """Train both, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, default=2, help="env processes of each library")
    parser.add_argument("--steps", type=int, default=24_000, help="env steps to train")
    parser.add_argument("--batch", type=int, default=6_000, help="env steps per PPO update")
    args = parser.parse_args()
    from flowrun.training.rllib import train_rllib
    from flowrun.training.trainer import train

    sb3_cfg, rllib_cfg = configs(args.envs, args.steps, args.batch)
    print(
        f"ring: {CONFIG.name}, {args.envs} env processes, {args.steps} env steps, "
        f"PPO batch {args.batch}, {os.cpu_count()} cores; load before: {load()}"
    )
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-rllib-") as out:
        for name, run in (("stable-baselines3", train), ("RLlib", train_rllib)):
            cfg = sb3_cfg if name == "stable-baselines3" else rllib_cfg
            start = time.perf_counter()
            result = run(cfg, out=Path(out), argv=["bench/rllib_vs_sb3.py"])
            total = time.perf_counter() - start
            rows.append((name, result.timesteps, result.steps_per_second, total))
            print(f"  {name} done; load: {load()}", flush=True)
    print(f"{'library':<18} {'env steps':>9} {'steps/s':>9} {'time to result (s)':>19}")
    for name, steps, rate, total in rows:
        print(f"{name:<18} {steps:>9} {rate:>9.0f} {total:>19.1f}")
    print(f"load after: {load()}")


if __name__ == "__main__":
    main()
