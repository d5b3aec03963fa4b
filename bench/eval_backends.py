"""One periodic evaluation of ``train.eval_backend: sumo`` against ``numpy``, in one run.

Builds both evaluation runners for the config (the same seeds and ring lengths the trainer
uses), times their all-human baselines and ``--repeats`` evaluations of one policy (a fresh
PPO MLP of the config's ``net_arch`` behind the numpy copy the trainer uses, observations
unnormalised), and prints seconds per evaluation, the ratio, and the largest difference
between the two backends' scores.

    .venv/bin/python bench/eval_backends.py [--config configs/ring_wave.yaml] [--repeats 2]
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace
from typing import Any

from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config
from flowrun.training.algorithms import algorithm_class
from flowrun.training.numpy_eval import NumpyEpisodeRunner
from flowrun.training.periodic_eval import EpisodeRunner, numpy_policy


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", default="configs/ring_wave.yaml")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    cfg = load_config(args.config)
    tc = cfg.train
    assert tc is not None, "the config needs a train: section"
    seeds = [args.seed + 10_000 + i for i in range(tc.eval_episodes)]
    env = make_env(cfg)
    cls: Any = algorithm_class("PPO")
    model = cls("MlpPolicy", env, policy_kwargs=dict(tc.policy_kwargs), seed=args.seed,
                device="cpu")
    env.close()
    act = numpy_policy(model.policy)
    assert act is not None
    print(f"{args.config}: {len(seeds)} episodes per evaluation, load "
          f"{os.getloadavg()[0]:.2f}")
    results: dict[str, tuple[float, float, list[float]]] = {}
    for name in ("sumo", "numpy"):
        start = time.perf_counter()
        if name == "numpy":
            runner: Any = NumpyEpisodeRunner(cfg, seeds)
        else:
            runner = EpisodeRunner(replace(cfg, env=replace(cfg.env, evaluate=True)), seeds)
        built = time.perf_counter() - start
        start = time.perf_counter()
        for _ in range(args.repeats):
            scores = runner.run(act, None)
        each = (time.perf_counter() - start) / args.repeats
        runner.close()
        assert scores is not None
        results[name] = (built, each, [s.last_half_speed for s in scores])
        print(f"  {name:5s}: set-up + all-human baseline {built:6.2f} s, "
              f"one evaluation {each:6.2f} s")
    ratio = results["sumo"][1] / results["numpy"][1]
    diff = max(abs(a - b) for a, b in zip(results["sumo"][2], results["numpy"][2], strict=True))
    print(f"  numpy is {ratio:.1f}x cheaper per evaluation; largest difference of an episode's "
          f"last-half mean speed: {diff:.2e} m/s; load {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
