"""Cost of a simulation step on the Sugiyama ring: raw SUMO (the floor) vs flowrun.

Run: ``.venv/bin/python bench/ring.py`` (add ``--long`` for the 100,000-step memory check).
See ``bench/README.md`` for what each number means. All numbers come from this one run:
every repetition times every mode once, in turn, and the medians are reported.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import version
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.envs.base import Env
from flowrun.envs.factory import make_env
from flowrun.experiment import Experiment
from flowrun.experiment.baseline import open_run_log
from flowrun.loading.loader import load_config
from flowrun.recording.writer import McapRecorder

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
SUMO_IDM = (
    "vehicles[0].acceleration_controller={type: SimCarFollowingController}",
    "vehicles[0].car_following.car_follow_model=IDM",
)


@dataclass(frozen=True)
class Ring:
    """One ring size: 22 cars on 230 m, or the same density scaled up."""

    label: str
    scale: int  # vehicles = 22 * scale, length = 230 m * scale (bunching scaled too)
    steps: int  # timed steps per repetition
    warmup: int  # untimed steps before them

    @property
    def vehicles(self) -> int:
        return 22 * self.scale

    def overrides(self, steps_total: int) -> list[str]:
        return [
            f"vehicles[0].count={self.vehicles}",
            f"network.length={230 * self.scale}",
            f"initial.bunching={20 * self.scale}",
            f"env.horizon={steps_total}",
        ]


def config(name: str, ring: Ring, *extra: str) -> ExperimentConfig:
    return load_config(
        CONFIGS / f"{name}.yaml", [*ring.overrides(ring.warmup + ring.steps), *extra]
    )


def time_floor(ring: Ring) -> float:
    """(a) SUMO's own IDM drives; libsumo is stepped with no per-vehicle Python call (µs/step).

    flowrun only builds the network and inserts the cars; each car then gets a route of many
    laps once, so that no router has to run while the clock runs.
    """
    env = make_env(config("sugiyama", ring, *SUMO_IDM))
    try:
        env.reset(seed=0)
        assert env.k.process is not None
        api = env.k.process.api
        edges = [e.id for e in env.k.network.spec.edges]
        travel = (ring.warmup + ring.steps) * env.sim_step * env.k.network.max_speed()
        laps = math.ceil(travel / env.k.network.length()) + 2
        for vid in env.k.vehicle.get_ids():
            i = edges.index(api.vehicle.getRoadID(vid))
            api.vehicle.setRoute(vid, (edges[i:] + edges[:i]) * laps)
        step = api.simulationStep
        for _ in range(ring.warmup):
            step()
        t0 = time.perf_counter()
        for _ in range(ring.steps):
            step()
        elapsed = time.perf_counter() - t0
        assert api.vehicle.getIDCount() == ring.vehicles, "a car left the ring"
        assert api.simulation.getCollidingVehiclesNumber() == 0
        return elapsed / ring.steps * 1e6
    finally:
        env.close()


def time_env_steps(env: Env, ring: Ring, action: Any = None) -> float:
    """``env.step`` in a loop, no statistics or frames collected (µs/step)."""
    env.reset(seed=0)
    for _ in range(ring.warmup):
        env.step(action)
    t0 = time.perf_counter()
    for _ in range(ring.steps):
        env.step(action)
    elapsed = time.perf_counter() - t0
    assert env.k.simulation.collisions == 0
    return elapsed / ring.steps * 1e6


def time_experiment(cfg: ExperimentConfig, ring: Ring, record: bool, tmp: Path) -> float:
    """(b)/(c): what ``flowrun baseline [--no-record]`` runs per step (µs/step).

    ``Experiment.run`` with per-step statistics (metrics.json) and, for (c), an MCAP recorder
    as the baseline command sets it up. The clock starts after ``warmup`` steps (reset
    excluded) and stops when ``run`` returns (the log's final chunk and footer included).
    """
    env = make_env(cfg, work_dir=tmp / "sumo")
    marks = {"t0": time.perf_counter()}  # replaced at the end of the warm-up

    def progress(run: int, step: int) -> None:
        if step == ring.warmup:
            marks["t0"] = time.perf_counter()

    def sink(run: int) -> McapRecorder:
        return open_run_log(tmp / f"run_{run}.mcap", env, cfg, 0, run)

    try:
        experiment = Experiment(env, sink_factory=sink if record else None, progress=progress)
        experiment.run(1, ring.warmup + ring.steps, seed=0)
        elapsed = time.perf_counter() - marks["t0"]
        assert experiment.metrics[0].collisions == 0
        return elapsed / ring.steps * 1e6
    finally:
        env.close()


def measure(ring: Ring, reps: int, with_wave_env: bool) -> dict[str, list[float]]:
    """µs/step of every mode, ``reps`` times, modes interleaved."""
    times: dict[str, list[float]] = {}
    for _ in range(reps):
        with tempfile.TemporaryDirectory() as tmp:
            runs: dict[str, Callable[[], float]] = {
                "a": lambda: time_floor(ring),
                "b0": lambda: _env_loop(config("sugiyama", ring), ring),
                "b": lambda: time_experiment(config("sugiyama", ring), ring, False, Path(tmp)),
                "c": lambda: time_experiment(config("sugiyama", ring), ring, True, Path(tmp)),
            }
            if with_wave_env:
                runs["wave"] = lambda: _wave_env(ring)
            for key, fn in runs.items():
                times.setdefault(key, []).append(fn())
    return times


def _env_loop(cfg: ExperimentConfig, ring: Ring) -> float:
    env = make_env(cfg)
    try:
        return time_env_steps(env, ring)
    finally:
        env.close()


def _wave_env(ring: Ring) -> float:
    # 21 noisy IDM cars + 1 RL car; the ring length is redrawn in [220, 270] m at each reset.
    cfg = load_config(
        CONFIGS / "ring_wave.yaml",
        [f"env.horizon={ring.warmup + ring.steps}", "env.warmup_steps=0"],
    )
    env = make_env(cfg)
    try:
        return time_env_steps(env, ring, action=np.zeros(1, dtype=np.float32))
    finally:
        env.close()


ROWS = (
    ("a", "(a) raw SUMO, SUMO's own IDM (floor)"),
    ("b0", "    env.step loop only (flowrun IDM)"),
    ("b", "(b) flowrun baseline, no recording"),
    ("c", "(c) flowrun baseline, MCAP recording"),
    ("wave", "    WaveAttenuationPOEnv.step"),
)


def report(ring: Ring, times: dict[str, list[float]]) -> None:
    med = {k: statistics.median(v) for k, v in times.items()}
    floor = med["a"]
    print(
        f"\nring {230 * ring.scale:,} m, {ring.vehicles:,} vehicles "
        f"({ring.steps} timed steps after {ring.warmup} warm-up, median of {len(times['a'])})"
    )
    print(f"  {'':40} {'µs/step':>10} {'steps/s':>10} {'x floor':>8}   range µs/step")
    for key, label in ROWS:
        if key not in med:
            continue
        us = med[key]
        lo, hi = min(times[key]), max(times[key])
        print(f"  {label:40} {us:10.1f} {1e6 / us:10,.0f} {us / floor:7.2f}x   {lo:.1f}-{hi:.1f}")
    print(
        f"  ratios: b/a = {med['b'] / floor:.2f}, c/a = {med['c'] / floor:.2f}; flowrun's own "
        f"work per vehicle (b-a)/n = {(med['b'] - floor) / ring.vehicles:.2f} µs, "
        f"recording (c-b)/n = {(med['c'] - med['b']) / ring.vehicles:.2f} µs"
    )
    # Two load-robust views of the same runs: the ratio within each repetition (a and b ran
    # seconds apart), and the fastest repetition of each mode (the least disturbed one).
    per_rep = {k: [x / y for x, y in zip(times[k], times["a"], strict=True)] for k in "bc"}
    best = {k: min(times[k]) for k in "abc"}
    print(
        "  per-repetition ratios, median (range): "
        + ", ".join(
            f"{k}/a = {statistics.median(v):.2f} ({min(v):.2f}-{max(v):.2f})"
            for k, v in per_rep.items()
        )
        + f"; fastest repetitions: b/a = {best['b'] / best['a']:.2f}, "
        f"c/a = {best['c'] / best['a']:.2f}"
    )


# --- memory (each in a fresh child process, so nothing else inflates the peak) -------------


def _proc_status_mb(key: str) -> float:
    """A ``kB`` field of ``/proc/self/status`` in MiB (``nan`` without ``/proc``)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return math.nan


def rss_now_mb() -> float:
    """Resident set size of this process now, MiB (Linux /proc)."""
    return _proc_status_mb("VmRSS")


def peak_rss_mb() -> float:
    """Peak resident set size of this process, MiB.

    ``VmHWM`` (the high-water mark of this process's own memory map). On Linux,
    ``resource.getrusage(...).ru_maxrss`` of a child started by ``subprocess`` also counts
    the parent's pages at the time of the fork, so it would report the benchmark's own
    peak instead; it is the fallback where ``/proc`` does not exist.
    """
    hwm = _proc_status_mb("VmHWM")
    if math.isnan(hwm):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return hwm


def child_peak(scale: int, steps: int) -> dict[str, float]:
    """(b) for ``steps`` steps; peak RSS."""
    ring = Ring("", scale, steps, 0)
    with tempfile.TemporaryDirectory() as tmp:
        time_experiment(config("sugiyama", ring), ring, False, Path(tmp))
    return {"peak_mb": peak_rss_mb()}


def child_long(steps: int, experiment: bool) -> dict[str, float]:
    """RSS at checkpoints of one long run at 22 cars: (b), or a bare env.step loop."""
    ring = Ring("", 1, steps, 0)
    cfg = config("sugiyama", ring)
    marks = {steps // 10, steps // 4, steps // 2, steps}
    rss: dict[str, float] = {}
    if experiment:
        env = make_env(cfg)

        def progress(run: int, step: int) -> None:
            if step in marks:
                rss[str(step)] = rss_now_mb()

        Experiment(env, progress=progress).run(1, steps, seed=0)
        env.close()
    else:
        env = make_env(cfg)
        env.reset(seed=0)
        for step in range(1, steps + 1):
            env.step(None)
            if step in marks:
                rss[str(step)] = rss_now_mb()
        env.close()
    rss["peak"] = peak_rss_mb()
    return rss


def in_child(*args: str) -> dict[str, float]:
    out = subprocess.run(
        [sys.executable, __file__, "--child", *args], capture_output=True, text=True, check=True
    )
    result: dict[str, float] = json.loads(out.stdout.strip().splitlines()[-1])
    return result


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--reps", type=int, default=5, help="repetitions per mode (median)")
    p.add_argument("--steps", type=int, default=3000, help="timed steps, 22-car ring")
    p.add_argument("--big-steps", type=int, default=200, help="timed steps, 2,200-car ring")
    p.add_argument("--big-reps", type=int, default=3, help="repetitions, 2,200-car ring")
    p.add_argument("--long", action="store_true", help="also: RSS over a 100,000-step run")
    p.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.child:
        kind, *rest = args.child
        if kind == "peak":
            res = child_peak(int(rest[0]), int(rest[1]))
        else:
            res = child_long(int(rest[0]), rest[1] == "experiment")
        print(json.dumps(res))
        return

    print(
        f"flowrun ring benchmark: SUMO {version('eclipse-sumo')} (libsumo), Python "
        f"{platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    small = Ring("small", 1, args.steps, max(args.steps // 10, 100))
    big = Ring("big", 100, args.big_steps, max(args.big_steps // 3, 50))
    report(small, measure(small, args.reps, with_wave_env=True))
    report(big, measure(big, args.big_reps, with_wave_env=False))

    print("\nmemory of (b), fresh process each")
    for scale, steps in ((1, 3000), (100, 300)):
        peak = in_child("peak", str(scale), str(steps))["peak_mb"]
        print(f"  peak RSS, {22 * scale:>5} vehicles, {steps} steps: {peak:7.1f} MiB")
    if args.long:
        n = 100_000
        for kind, label in (
            ("experiment", "(b) baseline, no recording"),
            ("env", "env.step loop only"),
        ):
            r = in_child("long", str(n), kind)
            checkpoints = ", ".join(f"{int(k):,}: {v:.1f}" for k, v in r.items() if k != "peak")
            growth = r[str(n)] - r[str(n // 10)]
            print(
                f"  {label}, 22 vehicles, {n:,} steps: RSS MiB at step {checkpoints}; "
                f"growth after step {n // 10:,}: {growth:+.1f} MiB "
                f"({growth * 2**20 / (n - n // 10):.0f} B/step); peak {r['peak']:.1f} MiB"
            )


if __name__ == "__main__":
    main()
