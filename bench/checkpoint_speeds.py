"""Every checkpoint of a ring training run, on SUMO rings of fixed lengths: where in training
the deterministic policy was good, and on which rings.

For each ``checkpoints/model_<steps>.zip`` (with its ``vecnormalize_<steps>.pkl``) and
``best_model.zip``: ``--episodes`` episodes (reset seeds ``sim.seed + i``, as ``flowrun eval``)
on a ring of each ``--lengths`` metres, last-half mean speed as % of the uniform-flow IDM speed
(``bench/train_target.py``'s reference). Save checkpoints often to see much, e.g.
``flowrun train configs/ring_wave.yaml --set train.checkpoint_freq=6000``.

    .venv/bin/python bench/checkpoint_speeds.py RUN_DIR [--lengths 230 260] [--episodes 1]
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np
from train_target import equilibrium_speed  # bench/ is this script's folder

from flowrun.envs.factory import make_env
from flowrun.training.algorithms import algorithm_class
from flowrun.training.evaluate import eval_config, load_normalize
from flowrun.training.periodic_eval import numpy_policy, play_episode, torch_policy
from flowrun.training.trainer import BEST_MODEL, BEST_VECNORMALIZE, train_section


def models(run: Path) -> list[tuple[str, Path, Path]]:
    """(label, model, normalisation stats) of every checkpoint, in step order, then the best."""
    found = []
    for path in (run / "checkpoints").glob("model_*.zip"):
        steps = int(re.findall(r"\d+", path.stem)[0])
        found.append((steps, path, path.with_name(f"vecnormalize_{steps}.pkl")))
    out = [(f"{s} steps", m, n) for s, m, n in sorted(found)]
    if (run / BEST_MODEL).is_file():
        out.append(("best_model", run / BEST_MODEL, run / BEST_VECNORMALIZE))
    return out


def main() -> None:
    """Print one row per model: % of the uniform-flow speed at each length."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run", type=Path)
    p.add_argument("--lengths", type=int, nargs="+", default=[230, 260])
    p.add_argument("--episodes", type=int, default=1)
    args = p.parse_args()
    cfg = eval_config(args.run)
    tc = train_section(cfg)
    eq = {L: equilibrium_speed(str(args.run / "config.yaml"), L) for L in args.lengths}
    table: dict[str, list[float]] = {}
    for length in args.lengths:
        env = make_env(
            eval_config(args.run, [f"env.additional_params.ring_length=[{length}, {length}]"])
        )
        try:
            for label, path, stats in models(args.run):
                model = algorithm_class(tc.algorithm).load(path, device="cpu")
                act = numpy_policy(model.policy) or torch_policy(model)
                norm = load_normalize(stats).normalize_obs if tc.normalize else None
                speeds = []
                for i in range(args.episodes):
                    played = play_episode(env, int(cfg.sim.seed or 0) + i, act, norm)
                    assert played is not None
                    speeds.append(played.last_half_speed)
                table.setdefault(label, []).append(100 * float(np.mean(speeds)) / eq[length])
        finally:
            env.close()
    print("| model | " + " | ".join(f"{L} m" for L in args.lengths) + " |")
    print("|---|" + "---:|" * len(args.lengths))
    for label, pcts in table.items():
        print(f"| {label} | " + " | ".join(f"{x:.1f} %" for x in pcts) + " |")


if __name__ == "__main__":
    main()
