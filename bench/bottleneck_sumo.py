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
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from paper_sumo import (  # bench/, beside this file
    Setup,
    run,
    sumo_options,
    traci_and_sumo,
    write_setup,
)

CONFIG = Path(__file__).resolve().parent.parent / "configs" / "bottleneck.yaml"


def write_files(inflow: float, out: Path, overrides: tuple[str, ...], seconds: float) -> Setup:
    """The ``.net.xml`` and ``.rou.xml`` flowrun builds for ``configs/bottleneck.yaml`` at
    ``inflow`` veh/h, to be run for ``seconds`` (one simulation step per env step)."""
    from flowrun.loading.loader import load_config

    cfg = load_config(CONFIG, [f"network.inflows.0.vehs_per_hour={inflow}", *overrides])
    setup = write_setup(cfg, out, f"bottleneck-{inflow:.0f}", speed=False)
    return replace(setup, sims_per_step=1, env_steps=round(seconds / setup.step))


def table_options(parser: argparse.ArgumentParser, inflows: str) -> None:
    """The options of an outflow-inflow table (``capacity_drop.py``'s too)."""
    parser.add_argument("--inflows", default=inflows, help="comma-separated inflows, veh/h")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=800.0)
    parser.add_argument("--window", type=float, default=500.0)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="config override, as flowrun's --set (repeatable)")  # fmt: skip


def print_table(args: argparse.Namespace, what: str, last: str,
                runs: Callable[[float], Sequence[tuple[float, float]]],
                total: Callable[[list[float]], float]) -> None:  # fmt: skip
    """Print an outflow-inflow table in Markdown: a line saying ``what`` ran, then per inflow
    of ``args.inflows`` the mean outflow of its ``runs`` (one ``(outflow, x)`` per seed), the
    std over seeds, and ``total`` of the runs' ``x`` in column ``last``."""
    print(f"{what}, {args.seconds:.0f} s per run, outflow over the last {args.window:.0f} s, "
          f"{args.seeds} seed(s) {' '.join(args.set)}\n")  # fmt: skip
    print(f"| inflow (veh/h) | outflow (veh/h) | std | {last} |")
    print("|---:|---:|---:|---:|")
    for inflow in (float(v) for v in args.inflows.split(",")):
        pairs = runs(inflow)
        out = [o for o, _ in pairs]
        std = statistics.stdev(out) if len(out) > 1 else 0.0
        print(f"| {inflow:.0f} | {statistics.mean(out):.0f} | {std:.0f} | "
              f"{total([x for _, x in pairs]):.0f} |")  # fmt: skip


def main() -> None:
    """Print the outflow-inflow table of one SUMO build."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sumo_options(parser)
    table_options(parser, "1600,2000,2100,2300,2500,3200")
    args = parser.parse_args()
    traci, sumo = traci_and_sumo(args)
    with tempfile.TemporaryDirectory() as tmp:

        def runs(inflow: float) -> list[tuple[float, int]]:
            setup = write_files(inflow, Path(tmp), tuple(args.set), args.seconds)
            return [run(traci, sumo, setup, s, args.window) for s in range(args.seeds)]

        print_table(args, f"{sumo} (traci {traci.__file__})", "teleports", runs, sum)


if __name__ == "__main__":
    main()
