"""flowrun's all-human baselines against the paper's set-up, one difference at a time.

Run: ``.venv/bin/python bench/paper_baselines.py [figureeight0 merge0 bottleneck0 grid0]
[--seeds 3]`` (about 4 min for all four at 3 seeds on a quiet machine).

Each row is ``flowrun benchmark``'s baseline of a benchmark (``flowrun baseline CONFIG`` with
the benchmark's ``--set`` overrides, evaluate mode), then with the settings of the paper's
code (Flow commit bc44b21, ``flow/benchmarks/baselines/``, Vinitsky et al. 2018) added one by
one, on the SUMO flowrun runs. The metric is ``flowrun benchmark``'s: mean speed (figure eight,
merge), the evaluate-mode return (grid: the sum over 400 steps of -(mean delay per car), s;
bottleneck: the outflow over the last 500 s, veh/h). ``docs/benchmark-baselines.md`` reads
the table.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
CONFIGS = ROOT / "configs" / "benchmarks"

_TYPE_2018 = ("vehicles.0.car_following.accel=1.0", "vehicles.0.car_following.decel=1.5")
_FLOW_LATER_F8 = ("vehicles.0.car_following.accel=2.6", "vehicles.0.car_following.decel=4.5",
                  "vehicles.0.car_following.min_gap=2.5",
                  "vehicles.0.acceleration_controller.noise=0.2")  # fmt: skip
_GRID_PHASES = (
    "[{duration: 31, minDur: 5, maxDur: 45, state: GrGr}, {duration: 2, minDur: 2, maxDur: 2, "
    "state: yryr}, {duration: 31, minDur: 5, maxDur: 45, state: rGrG}, {duration: 2, minDur: 2, "
    "maxDur: 2, state: ryry}]"
)
#: The grid baseline's actuated program at bc44b21 (its 12-character states, written for
#: junctions with turning links, on flowrun's straight-only junctions of 4 links).
_LIGHTS = ", ".join(
    f"{{node_id: center{i}, tls_type: actuated, programID: 1, phases: {_GRID_PHASES}}}"
    for i in range(9)
)
_GRID_PAPER_LIGHTS = f"traffic_lights={{lights: [{_LIGHTS}]}}"
_GRID_DEPART_MAX = tuple(f"network.inflows.{i}.depart_speed=max" for i in range(12))
#: Not an override: Flow 2018's rule that its controllers command cars on junction-internal
#: lanes too (Flow leaves them to SUMO since 2019, as flowrun does); run by :func:`junction_run`.
JUNCTION_RULE = ("<Flow 2018: controllers on junction lanes>",)

#: (benchmark, label, overrides on top of the benchmark's baseline), cumulative per benchmark.
VARIANTS: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    ("figureeight0", "flowrun (the paper's vehicles)", ()),
    (
        "figureeight0",
        "Flow's later vehicles: accel 2.6, decel 4.5, minGap 2.5, noise 0.2",
        _FLOW_LATER_F8,
    ),
    (
        "figureeight0",
        "the paper's vehicles + Flow 2018's controllers on junction lanes too",
        JUNCTION_RULE,
    ),
    ("merge0", "flowrun (Flow's later vehicles, 750 x 2 x 0.5 s)", ()),
    ("merge0", "+ the paper's 750 x 5 x 0.5 s", ("env.sims_per_step=5",)),
    (
        "merge0",
        "+ the paper's vehicle type: accel 1.0, decel 1.5",
        ("env.sims_per_step=5", *_TYPE_2018),
    ),
    ("bottleneck0", "flowrun (2,500 veh/h, 40 + 1500 steps, Flow's later vehicles)", ()),
    ("bottleneck0", "+ the paper's 1,900 veh/h", ("network.inflows.0.vehs_per_hour=1900",)),
    (
        "bottleneck0",
        "+ the paper's window: outflow of the first 500 s",
        ("network.inflows.0.vehs_per_hour=1900", "env.horizon=960"),
    ),
    (
        "bottleneck0",
        "+ the paper's vehicle type: accel 1.0, decel 1.5",
        ("network.inflows.0.vehs_per_hour=1900", "env.horizon=960", *_TYPE_2018),
    ),
    ("grid0", "flowrun (SUMO's actuated lights: green 31 s [8, 45], yellow 6 s)", ()),
    (
        "grid0",
        "the paper's actuated lights: green 31 s [5, 45], yellow 2 s",
        (_GRID_PAPER_LIGHTS, *_GRID_DEPART_MAX),
    ),
    (
        "grid0",
        "+ the paper's vehicle type: accel 1.0, decel 1.5",
        (_GRID_PAPER_LIGHTS, *_GRID_DEPART_MAX, *_TYPE_2018),
    ),
)


def junction_run(seed: int) -> float:
    """figureeight0's baseline (mean over the 1500 steps of the mean speed) with every car's
    controller commanding it on junction-internal lanes as well (flowrun's kernel patched)."""
    import numpy as np

    import flowrun.kernel.state as state
    from flowrun.envs.factory import make_env
    from flowrun.experiment.benchmark import BENCHMARKS
    from flowrun.loading.loader import load_config

    def command_all(self: object, acc: Any, idx: Any) -> Any:
        return acc

    state.OpenState.commandable = command_all  # type: ignore[method-assign]
    state.RingState.commandable = command_all  # type: ignore[method-assign]
    overrides = list(BENCHMARKS["figureeight0"].baseline)
    env = make_env(load_config(CONFIGS / "figureeight0.yaml", overrides))
    try:
        env.reset(seed=seed)
        speeds = []
        for _ in range(1500):
            env.step(None)
            speeds.append(float(np.mean(env.k.vehicle.get_speed(env.k.vehicle.get_ids()))))
    finally:
        env.close()
    return statistics.fmean(speeds)


def measure(name: str, sets: tuple[str, ...], seed: int, out: Path) -> float:
    """The benchmark metric of one ``flowrun baseline`` run."""
    from flowrun.experiment.benchmark import BENCHMARKS

    if sets == JUNCTION_RULE:  # its own process: the patch must not reach other runs
        cmd = [sys.executable, __file__, "--junction-run", str(seed)]
        done = subprocess.run(cmd, check=True, capture_output=True, text=True, cwd=ROOT)
        return float(done.stdout.split()[-1])
    bench = BENCHMARKS[name]
    overrides = [*bench.baseline, *sets]
    if name == "grid0" and sets:  # the paper's own lights instead of SUMO's default actuated
        overrides = [o for o in overrides if not o.startswith("traffic_lights.controller")]
    folder = out / f"{name}-{len(list(out.glob(name + '-*')))}-{seed}"
    cmd = [sys.executable, "-m", "flowrun.cli.main", "baseline", str(CONFIGS / f"{name}.yaml"),
           *[a for o in overrides for a in ("--set", o)], "--seed", str(seed), "--runs", "1",
           "--no-record", "--out", str(out), "--folder", str(folder)]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True, cwd=ROOT)
    row = json.loads((folder / "metrics.json").read_text())["runs"][0]
    return float(row[bench.metric.baseline_key])


def main() -> None:
    """Print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("benchmarks", nargs="*", default=["figureeight0", "merge0",
                                                          "bottleneck0", "grid0"])  # fmt: skip
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--junction-run", type=int, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.junction_run is not None:
        print(junction_run(args.junction_run))
        return
    print(f"seeds 0-{args.seeds - 1}; mean +- std (per-seed values)\n")
    print("| benchmark | set-up | metric |")
    print("|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, label, sets in VARIANTS:
            if name not in args.benchmarks:
                continue
            values = [measure(name, sets, s, Path(tmp)) for s in range(args.seeds)]
            std = statistics.stdev(values) if len(values) > 1 else 0.0
            each = ", ".join(f"{v:.4g}" for v in values)
            print(f"| {name} | {label} | {statistics.fmean(values):.4g} +- {std:.2g} ({each}) |",
                  flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
