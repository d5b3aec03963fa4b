"""The all-human merge0 / bottleneck0 baselines on any SUMO build, flowrun's or the paper's set-up.

Run: ``.venv/bin/python bench/paper_sumo.py merge0 --setup paper`` (the eclipse-sumo wheel's
SUMO) or, for another SUMO, ``--sumo BIN --traci DIR`` (DIR holds that version's ``traci``
package; ``bench/README.md`` says where older builds come from).

Both baselines have only SUMO-driven cars, so no flowrun kernel is needed to run them on
another SUMO: flowrun writes the benchmark's ``.net.xml`` (the wheel's netconvert, or
``--netconvert BIN``) and ``.rou.xml`` (its vehicle types and inflows), that SUMO runs them
over TraCI as Flow's kernel starts it, and each car gets its type's speed and lane-change
modes when it departs. The cars flowrun places at the start (5 on the merge, 1 on the
bottleneck) are left out. ``--setup flowrun`` is ``flowrun benchmark``'s baseline;
``--setup paper`` is the paper's (Flow commit bc44b21, ``flow/benchmarks/baselines/``): the
2018 vehicle type (accel 1.0, decel 1.5), the merge averaged over 750 steps of 5 x 0.5 s, the
bottleneck at 1,900 veh/h with its outflow over the first 500 s (:data:`PAPER`).

Printed per seed: the merge's mean speed (the mean over env steps of the mean speed of the
cars on the road, Flow's evaluate-mode reward) or the bottleneck's outflow (veh/h, cars leaving
edge 5 in the last 500 s), and the teleports (a Flow episode would end at the first).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

CONFIGS = Path(__file__).resolve().parent.parent / "configs" / "benchmarks"

_TYPE_2018 = ("vehicles.0.car_following.accel=1.0", "vehicles.0.car_following.decel=1.5")
#: The paper's baselines (Flow bc44b21) as overrides on top of ``flowrun benchmark``'s.
PAPER: dict[str, tuple[str, ...]] = {
    "merge0": (*_TYPE_2018, "env.sims_per_step=5"),
    "bottleneck0": (*_TYPE_2018, "network.inflows.0.vehs_per_hour=1900", "env.horizon=960"),
}


@dataclass(frozen=True)
class Setup:
    """What one run needs: files, step, how long, what to measure."""

    net: Path
    rou: Path
    modes: dict[str, tuple[int, int]]
    step: float
    sims_per_step: int
    env_steps: int
    speed: bool


def write_setup(cfg: Any, out: Path, stem: str, speed: bool) -> Setup:
    """flowrun's files of config ``cfg`` under ``out`` (the routes as ``stem.rou.xml``) and
    what a run of them needs; ``speed``: measure the mean speed, else the outflow."""
    import flowrun.networks.build as build
    from flowrun.envs.factory import make_env
    from flowrun.networks.routes import routes_xml

    env = make_env(cfg)
    try:
        network = env.network
        net = build.build_network(network.spec, out, cfg.name)
        rou = out / f"{stem}.rou.xml"
        rou.write_text(routes_xml(network.spec, network.vehicles, network.net_params.inflows))
        modes = {g.veh_id: (int(g.car_following_params.speed_mode),
                            int(g.lane_change_params.lane_change_mode))
                 for g in network.vehicles.groups}  # fmt: skip
    finally:
        env.close()
    e = cfg.env
    return Setup(net, rou, modes, cfg.sim.sim_step, e.sims_per_step,
                 int(e.warmup_steps + e.horizon), speed)  # fmt: skip


def write_files(name: str, setup: str, out: Path, sets: tuple[str, ...],
                netconvert: str | None = None) -> Setup:  # fmt: skip
    """flowrun's files of benchmark ``name``'s baseline (``setup``: flowrun or paper), the
    network by ``netconvert`` (default: the wheel's)."""
    import flowrun.networks.build as build
    from flowrun.experiment.benchmark import BENCHMARKS
    from flowrun.loading.loader import load_config

    if netconvert:
        wheel = build.sumo_binary

        def tool_path(name: str) -> str:
            return netconvert if name == "netconvert" else wheel(name)

        build.sumo_binary = tool_path
    overrides = [*BENCHMARKS[name].baseline, *(PAPER[name] if setup == "paper" else ()), *sets]
    cfg = load_config(CONFIGS / f"{name}.yaml", overrides)
    return write_setup(cfg, out, f"{name}-{setup}", name.startswith("merge"))


def run(traci: Any, sumo: str, s: Setup, seed: int, window_s: float = 500.0) -> tuple[float, int]:
    """(mean speed m/s, or outflow veh/h over the last ``window_s`` s; teleports) of one run
    over TraCI, started as Flow's kernel starts SUMO; each car gets its type's speed and
    lane-change modes when it departs."""
    traci.start([sumo, "-n", str(s.net), "-r", str(s.rou), "--step-length", str(s.step),
                 "--no-step-log", "true", "--no-warnings", "true", "--time-to-teleport", "-1",
                 "--collision.check-junctions", "true", "--seed", str(seed)])  # fmt: skip
    total = s.env_steps * s.sims_per_step
    window = round(window_s / s.step)
    speeds: list[float] = []
    arrived = teleports = 0
    try:
        for step in range(total):
            traci.simulationStep()
            for vid in traci.simulation.getDepartedIDList():
                speed_mode, lc_mode = s.modes[traci.vehicle.getTypeID(vid)]
                traci.vehicle.setSpeedMode(vid, speed_mode)
                traci.vehicle.setLaneChangeMode(vid, lc_mode)
            teleports += traci.simulation.getStartingTeleportNumber()
            if step >= total - window:
                arrived += traci.simulation.getArrivedNumber()
            if s.speed and (step + 1) % s.sims_per_step == 0:
                ids = traci.vehicle.getIDList()
                speeds.append(statistics.fmean(traci.vehicle.getSpeed(v) for v in ids)
                              if ids else 0.0)  # fmt: skip
    finally:
        traci.close()
    seconds = min(total, window) * s.step
    return (statistics.fmean(speeds) if s.speed else arrived * 3600.0 / seconds), teleports


def sumo_options(parser: argparse.ArgumentParser) -> None:
    """``--sumo BIN --traci DIR``: the SUMO build to run and its TraCI client."""
    parser.add_argument("--sumo", default=None, help="sumo binary (default: the wheel's)")
    parser.add_argument("--traci", default=None, help="folder holding that SUMO's traci")


def traci_and_sumo(args: argparse.Namespace) -> tuple[Any, str]:
    """The ``traci`` module of ``--traci`` (imported before anything imports the wheel's) and
    the sumo binary of ``--sumo`` (default: the wheel's)."""
    if args.traci:
        sys.path.insert(0, args.traci)  # that version's client, before the wheel's
    import traci

    from flowrun.networks.build import sumo_binary

    return traci, args.sumo or sumo_binary("sumo")


def main() -> None:
    """Print one benchmark's all-human baseline per seed on one SUMO build."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("benchmark", choices=sorted(PAPER))
    parser.add_argument("--setup", choices=("flowrun", "paper"), default="flowrun")
    sumo_options(parser)
    parser.add_argument(
        "--netconvert", default=None, help="netconvert binary (default: the wheel's)"
    )
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="config override, as flowrun's --set (repeatable)")  # fmt: skip
    args = parser.parse_args()
    traci, sumo = traci_and_sumo(args)
    with tempfile.TemporaryDirectory() as tmp:
        setup = write_files(args.benchmark, args.setup, Path(tmp), tuple(args.set), args.netconvert)
        what = "mean speed (m/s)" if setup.speed else "outflow, last 500 s (veh/h)"
        print(f"{args.benchmark}, {args.setup} set-up {' '.join(args.set)}: {sumo}, "
              f"{setup.env_steps} x {setup.sims_per_step} x {setup.step} s, {what}")  # fmt: skip
        runs = [run(traci, sumo, setup, seed) for seed in range(args.seeds)]
    for seed, (value, teleports) in enumerate(runs):
        print(f"seed {seed}: {value:.2f}  teleports {teleports}")
    values = [v for v, _ in runs]
    std = statistics.stdev(values) if len(values) > 1 else 0.0
    print(f"mean {statistics.fmean(values):.2f} +- {std:.2f} over {len(values)} seed(s)")


if __name__ == "__main__":
    main()
