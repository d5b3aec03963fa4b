"""Cost of a simulation step on open networks: SUMO alone (the floor) vs flowrun.

Run: ``.venv/bin/python bench/open_networks.py`` (about 5 min). See ``bench/README.md``. Two
cases, every mode timed in the same run, modes interleaved within each repetition:

- **merge**: ``configs/merge.yaml`` (Flow's merge0: 2,000 veh/h on the highway of which 10 %
  AVs, 100 veh/h on the ramp, 0.5 s steps), timed once the stop-and-go waves have formed.
- **highway**: Flow's ``HighwayNetwork`` with 4 lanes, cut into 500 m edges, long enough for
  ``n`` cars at about 18 cars per lane-km, filled from the start (``n`` cars placed at 27 m/s)
  and kept full by one inflow per lane; ``n`` = 250, 500, 1,000, 2,000.

The floor is SUMO alone on the same ``.net.xml`` and ``.rou.xml`` (same flows and vTypes):
flowrun builds the files and inserts the cars placed at the start, then only
``libsumo.simulationStep()`` runs, and SUMO's own car-following model (its IDM with the same
parameters) drives every car; no Python runs per car.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import version
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.envs.factory import make_env
from flowrun.experiment import Experiment
from flowrun.experiment.baseline import open_run_log
from flowrun.loading.loader import load_config
from flowrun.recording.writer import McapRecorder

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
IDM = "{type: IDM, v0: 30, T: 1, a: 1, b: 1.5, delta: 4, s0: 2, noise: 0}"
SUMO_IDM = "{type: SimCarFollowingController}"
# SUMO's IDM with flowrun's IDM parameters: a = accel, b = decel, T = tau, s0 = minGap
CAR_FOLLOWING = (
    "{car_follow_model: IDM, accel: 1, decel: 1.5, tau: 1, min_gap: 2, speed_mode: obey_safe_speed}"
)


@dataclass(frozen=True)
class Case:
    """One network and demand, and how long to run it.

    Attributes:
        label: heading of its table.
        config: ``config(floor)``: the experiment; ``floor=True``: SUMO's model drives.
        warmup: simulation steps before the clock starts (the network fills).
        steps: timed simulation steps.
        alt: a variant of (b), timed too: its label and ``alt(total_steps)``.
    """

    label: str
    config: Callable[[bool, int], ExperimentConfig]
    warmup: int
    steps: int
    alt: tuple[str, Callable[[int], ExperimentConfig]]


@dataclass
class Timing:
    """µs per simulation step, wall clock and this process's CPU time, and the cars in the
    network while timing.

    CPU time leaves out the time another process held the core (libsumo runs in this
    process, so SUMO's work is in it): on a shared machine it moves less than the wall clock.
    """

    us: float
    cpu_us: float
    cars: float


# ------------------------------------------------------------------------------ the cases
def merge_config(floor: bool, steps: int, flowrun_idm: bool = False) -> ExperimentConfig:
    """``configs/merge.yaml`` for ``steps`` simulation steps (humans: SUMO's model, as Flow's
    merge0; ``flowrun_idm``: flowrun's IDM commands every human car instead)."""
    extra = [f"vehicles[0].acceleration_controller={IDM}"] if flowrun_idm and not floor else []
    cfg = load_config(CONFIGS / "merge.yaml", extra)
    horizon = -(-steps // cfg.env.sims_per_step)
    return load_config(CONFIGS / "merge.yaml", [*extra, f"env.horizon={horizon}"])


DENSITY = 18.0  # cars per lane-km
SPEED = 27.0  # m/s: IDM's equilibrium speed at that density (55 m spacing)
LANES = 4


def highway_yaml(cars: int, steps: int, floor: bool) -> str:
    """A highway of ``cars`` cars at :data:`DENSITY`, one inflow per lane at the same flow."""
    length = cars / (LANES * DENSITY) * 1000.0
    q = DENSITY * SPEED * 3.6  # veh/h per lane
    inflows = "\n".join(
        f"    - {{edge: highway_0, veh_type: human, vehs_per_hour: {q:.0f}, depart_lane: {i}, "
        f"depart_speed: {SPEED}}}"
        for i in range(LANES)
    )
    return f"""name: highway_{cars}
sim: {{step: 0.5, seed: 0}}
env: {{class: TestEnv, horizon: {steps}, warmup_steps: 0}}
network:
  type: highway
  length: {length:.0f}
  lanes: {LANES}
  speed_limit: 30
  num_edges: {max(1, round(length / 500.0))}
  inflows:
{inflows}
vehicles:
  - id: human
    count: {cars}
    initial_speed: {SPEED}
    acceleration_controller: {SUMO_IDM if floor else IDM}
    car_following: {CAR_FOLLOWING}
    lane_change: {{lane_change_mode: sumo_default}}
initial: {{spacing: uniform, bunching: 0, perturbation: 0}}
"""


def highway_case(cars: int, folder: Path, warmup: int, steps: int) -> Case:
    def config(floor: bool, total: int) -> ExperimentConfig:
        path = folder / f"highway_{cars}_{'floor' if floor else 'flowrun'}.yaml"
        path.write_text(highway_yaml(cars, total, floor))
        return load_config(path, [])

    def sumo_driven(total: int) -> ExperimentConfig:
        return config(True, total)

    alt = ("(b) with SUMO's IDM (flowrun only reads)", sumo_driven)
    return Case(f"highway, {cars:,} cars placed", config, warmup, steps, alt)


# ------------------------------------------------------------------------------ the modes
def time_floor(case: Case, tmp: Path) -> Timing:
    """(a) SUMO alone: flowrun writes the files and inserts the placed cars, then only
    ``simulationStep`` runs.

    Like flowrun, each car that enters gets its vehicle type's speed and lane-change modes
    (two calls per entering car, not per car and step): SUMO's modes are TraCI settings that
    a route file cannot carry, and the lane-change mode decides whether highway cars make
    room for merging ones, so without them SUMO alone would drive another traffic.
    """
    env = make_env(case.config(True, case.warmup + case.steps), work_dir=tmp / "floor")
    try:
        env.reset(seed=0)
        assert env.k.process is not None
        api = env.k.process.api
        sim, veh, pop = api.simulation, api.vehicle, env.k.vehicle.table
        modes = {c.name: (c.speed_mode, c.lane_change_mode) for c in pop.classes}

        def step() -> None:
            api.simulationStep()
            for vid in sim.getDepartedIDList():
                speed_mode, lane_change_mode = modes.get(veh.getTypeID(vid), (31, 1621))
                veh.setSpeedMode(vid, speed_mode)
                veh.setLaneChangeMode(vid, lane_change_mode)

        for _ in range(case.warmup):
            step()
        before = api.vehicle.getIDCount()
        t0, c0 = time.perf_counter(), time.process_time()
        for _ in range(case.steps):
            step()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        cars = (before + api.vehicle.getIDCount()) / 2
        return Timing(wall / case.steps * 1e6, cpu / case.steps * 1e6, cars)
    finally:
        env.close()


def time_experiment(cfg: ExperimentConfig, case: Case, record: bool, tmp: Path) -> Timing:
    """(b)/(c): ``flowrun baseline [--no-record]``'s loop (``Experiment.run``: env steps,
    per-step statistics, and for (c) the MCAP recorder; the log's close included)."""
    env = make_env(cfg, work_dir=tmp / "sumo")
    per = cfg.env.sims_per_step
    warm_env, timed_env = -(-case.warmup // per), case.steps // per
    marks: dict[str, Any] = {"t0": time.perf_counter(), "c0": time.process_time(), "cars": 0}

    def progress(run: int, step: int) -> None:
        if step == warm_env:
            marks["cars"] = env.k.vehicle.num_vehicles
            marks["t0"], marks["c0"] = time.perf_counter(), time.process_time()

    def sink(run: int) -> McapRecorder:
        return open_run_log(tmp / f"run_{run}.mcap", env, cfg, 0, run)

    try:
        experiment = Experiment(env, sink_factory=sink if record else None, progress=progress)
        experiment.run(1, warm_env + timed_env, seed=0)
        wall, cpu = time.perf_counter() - marks["t0"], time.process_time() - marks["c0"]
        cars = (marks["cars"] + env.k.vehicle.num_vehicles) / 2
        steps = timed_env * per
        return Timing(wall / steps * 1e6, cpu / steps * 1e6, cars)
    finally:
        env.close()


ROWS = {
    "a": "(a) SUMO alone, SUMO's IDM (floor)",
    "b": "(b) flowrun baseline, no recording",
    "c": "(c) flowrun baseline, MCAP recording",
}


def measure(case: Case, reps: int) -> dict[str, list[Timing]]:
    """Every mode of ``case``, ``reps`` times, modes interleaved."""
    out: dict[str, list[Timing]] = {}
    total = case.warmup + case.steps
    for _ in range(reps):
        with tempfile.TemporaryDirectory() as tmp:
            runs: dict[str, Callable[[], Timing]] = {
                "a": lambda: time_floor(case, Path(tmp)),
                "b": lambda: time_experiment(case.config(False, total), case, False, Path(tmp)),
                "c": lambda: time_experiment(case.config(False, total), case, True, Path(tmp)),
                "alt": lambda: time_experiment(case.alt[1](total), case, False, Path(tmp)),
            }
            for key, run in runs.items():
                out.setdefault(key, []).append(run())
    return out


def report(case: Case, times: dict[str, list[Timing]]) -> dict[str, float]:
    """Print one table; returns the median µs/step (wall and CPU) and cars of each mode."""
    wall = {k: statistics.median(t.us for t in v) for k, v in times.items()}
    cpu = {k: statistics.median(t.cpu_us for t in v) for k, v in times.items()}
    cars = {k: statistics.mean(t.cars for t in v) for k, v in times.items()}
    print(
        f"\n{case.label} ({case.steps} timed steps after {case.warmup}, median of "
        f"{len(times['a'])}; cars in the network while timed: "
        + ", ".join(f"{k} {c:,.0f}" for k, c in cars.items())
        + ")"
    )
    print(
        f"  {'':44} {'µs/step':>9} {'steps/s':>8} {'x floor':>8}   {'CPU µs':>9} {'x floor':>8}"
        f" {'CPU µs/car':>10}   wall range"
    )
    labels = {**ROWS, "alt": "    " + case.alt[0]}
    for key, label in labels.items():
        us, lo, hi = wall[key], min(t.us for t in times[key]), max(t.us for t in times[key])
        print(
            f"  {label:44} {us:9.1f} {1e6 / us:8,.0f} {us / wall['a']:7.2f}x   "
            f"{cpu[key]:9.1f} {cpu[key] / cpu['a']:7.2f}x {cpu[key] / max(cars[key], 1.0):10.2f}"
            f"   {lo:.0f}-{hi:.0f}"
        )
    per_rep = {
        k: [x.us / y.us for x, y in zip(times[k], times["a"], strict=True)]
        for k in times
        if k != "a"
    }
    print(
        "  wall-clock ratios per repetition, median (range): "
        + ", ".join(
            f"{k}/a = {statistics.median(v):.2f} ({min(v):.2f}-{max(v):.2f})"
            for k, v in per_rep.items()
        )
    )
    return (
        {k: v for k, v in wall.items()}
        | {f"cpu_{k}": v for k, v in cpu.items()}
        | {f"cars_{k}": c for k, c in cars.items()}
    )


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--reps", type=int, default=5, help="repetitions of the merge (median)")
    p.add_argument("--big-reps", type=int, default=3, help="repetitions per highway size")
    p.add_argument("--sizes", default="250,500,1000,2000", help="highway sizes, cars (\"\": none)")
    p.add_argument("--steps", type=int, default=200, help="timed steps per highway size")
    args = p.parse_args()
    print(
        f"flowrun open-network benchmark: SUMO {version('eclipse-sumo')} (libsumo), Python "
        f"{platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    merge = Case(
        "merge (configs/merge.yaml, Flow's merge0 demand)", merge_config, 600, 900,
        ("(b) with flowrun's IDM on every human", lambda n: merge_config(False, n, True)),
    )  # fmt: skip
    report(merge, measure(merge, args.reps))
    summary = []
    with tempfile.TemporaryDirectory() as folder:
        for cars in (int(s) for s in args.sizes.split(",") if s.strip()):
            case = highway_case(cars, Path(folder), warmup=60, steps=args.steps)
            med = report(case, measure(case, args.big_reps))
            summary.append((cars, med))
    print(
        "\nhighway, CPU µs per car per step (flat = linear in the number of cars), and the "
        "ratios to the floor (CPU time; wall clock in brackets)"
    )
    print(f"  {'cars':>6} {'floor a/n':>10} {'b/n':>8} {'c/n':>8} {'(b-a)/n':>8} {'(c-b)/n':>8}"
          f" {'b/a':>13} {'c/a':>13}")  # fmt: skip
    for cars, med in summary:
        a, b, c = (med[f"cpu_{k}"] / med[f"cars_{k}"] for k in "abc")
        print(
            f"  {cars:6,} {a:10.2f} {b:8.2f} {c:8.2f} {b - a:8.2f} {c - b:8.2f} "
            f"{med['cpu_b'] / med['cpu_a']:6.2f} ({med['b'] / med['a']:.2f})"
            f" {med['cpu_c'] / med['cpu_a']:6.2f} ({med['c'] / med['a']:.2f})"
        )
    print(f"load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
