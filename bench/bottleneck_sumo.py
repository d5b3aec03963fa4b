"""The all-human bottleneck on any SUMO build: how much of the outflow is SUMO's version.

Run: ``.venv/bin/python bench/bottleneck_sumo.py`` (the eclipse-sumo wheel's SUMO, about a
minute) or, for another SUMO, ``--sumo BIN --traci DIR`` (DIR holds that version's ``traci``
package; both from a Debian package, see ``bench/README.md``).

flowrun writes the files of ``configs/bottleneck.yaml`` (the ``.net.xml``, by the wheel's
netconvert whichever SUMO runs it, and the ``.rou.xml`` with Flow's vehicle type and inflow);
then that SUMO runs them
over TraCI the way Flow's kernel starts it (``--collision.check-junctions``, no teleporting,
SUMO's own collision action and min-gap factor), each car gets Flow's speed and lane-change
modes when it departs, and nothing else runs per step: no flowrun kernel, no initial car.
The outflow is the cars leaving the end of edge ``5`` in the last ``--window`` seconds of
``--seconds``; ``teleports`` are what Flow's ``check_collision`` counts as a crash.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path
from typing import Any

CONFIG = Path(__file__).resolve().parent.parent / "configs" / "bottleneck.yaml"


def write_files(inflow: float, out: Path, overrides: tuple[str, ...]) -> tuple[Path, Path, Any]:
    """The ``.net.xml`` and ``.rou.xml`` flowrun builds for ``configs/bottleneck.yaml`` at
    ``inflow`` veh/h, and the config's vehicle groups (their speed and lane-change modes)."""
    from flowrun.envs.factory import make_env
    from flowrun.loading.loader import load_config
    from flowrun.networks.build import build_network
    from flowrun.networks.routes import routes_xml

    cfg = load_config(CONFIG, [f"network.inflows.0.vehs_per_hour={inflow}", *overrides])
    env = make_env(cfg)
    try:
        network = env.network
        net = build_network(network.spec, out, "bottleneck")
        rou = out / f"bottleneck-{inflow:.0f}.rou.xml"
        rou.write_text(routes_xml(network.spec, network.vehicles, network.net_params.inflows))
        return net, rou, network.vehicles.groups
    finally:
        env.close()


def run(traci: Any, sumo: str, net: Path, rou: Path, groups: Any, seed: int,
        seconds: float, window: float) -> tuple[float, int]:  # fmt: skip
    """Outflow (veh/h) over the last ``window`` s and the teleports of one run."""
    modes = {g.veh_id: (int(g.car_following_params.speed_mode),
                        int(g.lane_change_params.lane_change_mode)) for g in groups}  # fmt: skip
    traci.start([sumo, "-n", str(net), "-r", str(rou), "--step-length", "0.5",
                 "--no-step-log", "true", "--no-warnings", "true", "--time-to-teleport", "-1",
                 "--collision.check-junctions", "true", "--seed", str(seed)])  # fmt: skip
    steps, counted = round(seconds / 0.5), round(window / 0.5)
    arrived = teleports = 0
    try:
        for step in range(steps):
            traci.simulationStep()
            for vid in traci.simulation.getDepartedIDList():
                speed_mode, lc_mode = modes[traci.vehicle.getTypeID(vid)]
                traci.vehicle.setSpeedMode(vid, speed_mode)
                traci.vehicle.setLaneChangeMode(vid, lc_mode)
            teleports += traci.simulation.getStartingTeleportNumber()
            if step >= steps - counted:
                arrived += traci.simulation.getArrivedNumber()
    finally:
        traci.close()
    return arrived * 3600.0 / window, teleports


def main() -> None:
    """Print the outflow-inflow table of one SUMO build."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sumo", default=None, help="sumo binary (default: the wheel's)")
    parser.add_argument("--traci", default=None, help="folder holding that SUMO's traci")
    parser.add_argument("--inflows", default="1600,2000,2100,2300,2500,3200")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=800.0)
    parser.add_argument("--window", type=float, default=500.0)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="config override, as flowrun's --set (repeatable)")  # fmt: skip
    args = parser.parse_args()
    if args.traci:
        sys.path.insert(0, args.traci)  # that version's client, before the wheel's
    import traci

    from flowrun.networks.build import sumo_binary

    sumo = args.sumo or sumo_binary("sumo")
    print(f"{sumo} (traci {traci.__file__}), {args.seconds:.0f} s per run, outflow over the last "
          f"{args.window:.0f} s, {args.seeds} seed(s) {' '.join(args.set)}\n")  # fmt: skip
    print("| inflow (veh/h) | outflow (veh/h) | std | teleports |")
    print("|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for inflow in (float(v) for v in args.inflows.split(",")):
            net, rou, groups = write_files(inflow, Path(tmp), tuple(args.set))
            runs = [run(traci, sumo, net, rou, groups, s, args.seconds, args.window)
                    for s in range(args.seeds)]  # fmt: skip
            out = [o for o, _ in runs]
            std = statistics.stdev(out) if len(out) > 1 else 0.0
            print(f"| {inflow:.0f} | {statistics.mean(out):.0f} | {std:.0f} | "
                  f"{sum(t for _, t in runs)} |")  # fmt: skip


if __name__ == "__main__":
    main()
