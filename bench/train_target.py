"""Issue 14's training target: ``flowrun train`` per seed, then ``flowrun eval`` at 230 and 260 m.

For each seed: a fresh ``flowrun train CONFIG --seed S`` (wall-clock of the whole command,
its post-training evaluation included), the evaluation share of its training time (from
``metrics.json``), then ``flowrun eval RUN --episodes 3`` with the ring fixed at 230 m and at
260 m. The speed is the policy's last-half mean speed over the 3 episodes, as a percentage of
the uniform-flow (IDM equilibrium) speed of that ring. Target: >= 95 % at both lengths in
<= 180 s, for at least 2 of 3 seeds.

    .venv/bin/python bench/train_target.py [--config configs/ring_wave.yaml] [--seeds 0 1 2]
        [--out runs/train_target] [--set train.total_timesteps=...]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from flowrun.config.params import is_rl
from flowrun.controllers.car_following_formulas import idm_accel
from flowrun.loading.loader import load_config

FLOWRUN = str(Path(sys.executable).with_name("flowrun"))
LENGTHS = (230, 260)
TARGET_WALL_S = 180.0
TARGET_SHARE = 0.95


def equilibrium_speed(config: str, length: float) -> float:
    """Uniform-flow speed (m/s) of the config's human IDM drivers on a ring of ``length`` m."""
    cfg = load_config(config)
    human = next(g for g in cfg.vehicles.groups if not is_rl(g)).acceleration_controller
    p = {k: float(human.params[k]) for k in ("v0", "T", "a", "b", "delta", "s0")}
    gap = length / cfg.vehicles.num_vehicles - 5.0  # flowrun's default vehicle length
    lo, hi = 0.0, p["v0"]
    for _ in range(200):  # idm_accel(v, gap, v) falls as v rises: bisect for its zero
        mid = (lo + hi) / 2
        a = float(idm_accel(np.array([mid]), np.array([gap]), np.array([mid]), **p)[0])
        lo, hi = (mid, hi) if a > 0 else (lo, mid)
    return lo


def run(cmd: list[str]) -> float:
    """Run a command (output to this terminal's stderr); its wall-clock seconds."""
    start = time.perf_counter()
    done = subprocess.run(cmd, stdout=sys.stderr, stderr=sys.stderr, check=False)
    if done.returncode != 0:
        raise SystemExit(f"failed ({done.returncode}): {' '.join(cmd)}")
    return time.perf_counter() - start


def newest(folder: Path) -> Path:
    """The most recently created subfolder."""
    return max((p for p in folder.iterdir() if p.is_dir()), key=lambda p: p.stat().st_mtime)


def eval_speed(run_dir: Path, length: int, out: Path) -> float:
    """Last-half mean speed of the best policy over 3 episodes on a ring of ``length`` m."""
    out.mkdir(parents=True, exist_ok=True)
    run([FLOWRUN, "eval", str(run_dir), "--episodes", "3", "--out", str(out),
         "--set", f"env.additional_params.ring_length=[{length}, {length}]"])
    metrics = json.loads((newest(out) / "metrics.json").read_text())
    return float(metrics["policy_mean"]["last_half_mean_speed"])


def main() -> None:
    """Train and evaluate each seed; print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="configs/ring_wave.yaml")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--out", type=Path, default=Path("runs/train_target"))
    parser.add_argument("--set", dest="sets", action="append", default=[],
                        help="an override passed to flowrun train (repeatable)")
    args = parser.parse_args()
    name = load_config(args.config, args.sets).name
    eq = {L: equilibrium_speed(args.config, L) for L in LENGTHS}
    print(f"load before: {os.getloadavg()[0]:.2f} (1-min average); uniform-flow speed "
          + ", ".join(f"{L} m: {v:.3f} m/s" for L, v in eq.items()), flush=True)
    rows = []
    for seed in args.seeds:
        out = args.out / f"seed{seed}"
        sets = [a for s in args.sets for a in ("--set", s)]
        wall = run([FLOWRUN, "train", args.config, "--seed", str(seed), "--out", str(out),
                    *sets])
        run_dir = newest(out / name)
        timing = json.loads((run_dir / "metrics.json").read_text())["timing"]
        speeds = {L: eval_speed(run_dir, L, args.out / f"seed{seed}-eval{L}") for L in LENGTHS}
        pct = {L: 100 * speeds[L] / eq[L] for L in LENGTHS}
        ok = wall <= TARGET_WALL_S and all(p >= 100 * TARGET_SHARE for p in pct.values())
        rows.append((seed, wall, timing["evaluation_share"], pct, ok, os.getloadavg()[0]))
        print(f"seed {seed} done: {wall:.0f} s", flush=True)
    print()
    print("| seed | wall s | eval share | speed % 230 m | speed % 260 m | target met | load |")
    print("|---:|---:|---:|---:|---:|:---:|---:|")
    for seed, wall, share, pct, ok, load in rows:
        print(f"| {seed} | {wall:.0f} | {100 * share:.1f} % | {pct[230]:.1f} | {pct[260]:.1f} "
              f"| {'yes' if ok else 'no'} | {load:.2f} |")
    met = sum(r[4] for r in rows)
    print(f"\ntarget (>= 95 % at both lengths in <= {TARGET_WALL_S:.0f} s) met by {met} of "
          f"{len(rows)} seeds; load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
