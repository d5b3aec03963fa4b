"""Flow's eleven benchmarks (``flow/benchmarks/``): which config, which metric, which baseline.

Each benchmark is a shipped RL config (``configs/benchmarks/<name>.yaml``: Flow's horizon,
step, demand, penetration rate and env class; ``flowrun train`` trains it) and a non-RL
baseline derived from it by ``--set`` overrides, as Flow's ``flow/benchmarks/baselines/``
scripts define it:

* figure eight (``baselines/figureeight012.py``): 14 noisy IDM drivers and no AV, the same for
  figureeight0/1/2, with the humans of the configs (the paper's: noise 0.2 per 0.1 s step,
  speed mode 1, Flow's 2018 vehicle type: accel 1.0, decel 1.5, minGap 0, speedDev 0.1);
* merge (``baselines/merge012.py``): no AVs, all 2,000 veh/h of the highway human (the ramp's
  100 veh/h as before);
* grid (``baselines/grid0.py``, ``grid1.py``): the same cars, SUMO's actuated lights;
* bottleneck (``baselines/bottleneck0-2.py``): no AVs, the whole inflow human.

Every baseline runs with ``env.evaluate: true`` (Flow's baselines set it). Flow's evaluation
metric per family, read from a run's ``metrics.json`` row:

* mean speed (figure eight, merge): ``mean_speed``, m/s;
* -delay (grid): ``episode_return`` in evaluate mode, the sum over steps of -(mean delay per
  car in the step), s;
* outflow over the last 500 s at the horizon (bottleneck): ``outflow``, veh/h; in evaluate mode
  the env's episode return is the same number (its reward is 0 but at the horizon), which is
  what a trained policy's evaluation reports.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flowrun.errors import ConfigError
from flowrun.suggest import unknown_name

#: Families, in the order Flow's paper lists them.
FAMILIES = ("figureeight", "merge", "grid", "bottleneck")

_FIG8_HUMANS = (
    "vehicles=[{id: human, count: 14, acceleration_controller: {type: IDM, noise: 0.632}, "
    "routing_controller: {type: ContinuousRouter}, car_following: {speed_mode: obey_safe_speed, "
    "accel: 1.0, decel: 1.5, min_gap: 0, speed_dev: 0.1}}]"
)
_MERGE_HUMANS = (
    "network.inflows=[{edge: inflow_highway, veh_type: human, vehs_per_hour: 2000, "
    "depart_lane: free, depart_speed: 10}, {edge: inflow_merge, veh_type: human, "
    "vehs_per_hour: 100, depart_lane: free, depart_speed: 7.5}]"
)


def _bottleneck_humans(rate: int) -> tuple[str, ...]:
    inflow = (
        f'network.inflows=[{{edge: "1", veh_type: human, vehs_per_hour: {rate}, '
        "depart_lane: random, depart_speed: 10}]"
    )
    return (inflow, "vehicles.1.count=0")


@dataclass(frozen=True)
class Metric:
    """How a family is scored.

    Attributes:
        label: the metric's name in tables (``mean speed``, ``-delay``, ``outflow``).
        unit: its unit.
        baseline_key: the ``metrics.json`` run-row key of a baseline run.
        policy_key: the key of a policy evaluation's episode row (``flowrun eval``).
    """

    label: str
    unit: str
    baseline_key: str
    policy_key: str


SPEED = Metric("mean speed", "m/s", "mean_speed", "mean_speed")
DELAY = Metric("-delay", "s", "episode_return", "episode_return")
OUTFLOW = Metric("outflow, last 500 s", "veh/h", "outflow", "episode_return")


@dataclass(frozen=True)
class Benchmark:
    """One of Flow's benchmarks.

    Attributes:
        name: Flow's name (``figureeight0``), also the config's file name and ``name:``.
        family: ``figureeight``, ``merge``, ``grid`` or ``bottleneck``.
        metric: how it is scored.
        reference: the score ``flow/benchmarks/create_movies.sh`` checks a trained policy against
            (it passes at 95 %); ``None`` where Flow has no usable one.
        reference_note: why there is none, or ``""`` (tables show ``none *`` and the note).
        baseline: the ``--set`` overrides that turn the config into Flow's baseline.
    """

    name: str
    family: str
    metric: Metric
    reference: float | None
    reference_note: str
    baseline: tuple[str, ...]

    def config_path(self, folder: Path) -> Path:
        """``<folder>/<name>.yaml``."""
        return folder / f"{self.name}.yaml"

    @property
    def baseline_note(self) -> str:
        """What the baseline is, in a few words (``SUMO's actuated lights``)."""
        return BASELINE_NOTES[self.family]

    @property
    def network_type(self) -> str:
        """The ``network.type`` of its config (``figure_eight``)."""
        return FAMILY_NETWORKS[self.family]


#: What each family's baseline is, for tables and ``flowrun eval``.
BASELINE_NOTES = {
    "figureeight": "14 human drivers of the paper's vehicle type, no AV",
    "merge": "no AV, the whole inflow human",
    "grid": "SUMO's actuated lights",
    "bottleneck": "no AV, the whole inflow human",
}

#: Each family's network type (``network.type`` in its configs).
FAMILY_NETWORKS = {
    "figureeight": "figure_eight",
    "merge": "merge",
    "grid": "traffic_light_grid",
    "bottleneck": "bottleneck",
}


_GRID_NOTE = (
    "Flow's flow/benchmarks/create_movies.sh checks grid0/grid1 against 296, a number it reads "
    "from the visualizer's outflow line (rew=${outflow_arr[3]}), not from the return: no -delay "
    "reference exists"
)
_EVAL = "env.evaluate=true"
BENCHMARKS: dict[str, Benchmark] = {
    b.name: b
    for b in (
        Benchmark("figureeight0", "figureeight", SPEED, 7.3, "", (_FIG8_HUMANS, _EVAL)),
        Benchmark("figureeight1", "figureeight", SPEED, 6.4, "", (_FIG8_HUMANS, _EVAL)),
        Benchmark("figureeight2", "figureeight", SPEED, 5.7, "", (_FIG8_HUMANS, _EVAL)),
        Benchmark("merge0", "merge", SPEED, 13.0, "", (_MERGE_HUMANS, _EVAL)),
        Benchmark("merge1", "merge", SPEED, 13.0, "", (_MERGE_HUMANS, _EVAL)),
        Benchmark("merge2", "merge", SPEED, 13.0, "", (_MERGE_HUMANS, _EVAL)),
        Benchmark("grid0", "grid", DELAY, None, _GRID_NOTE,
                  ("traffic_lights.controller=actuated", _EVAL)),
        Benchmark("grid1", "grid", DELAY, None, _GRID_NOTE,
                  ("traffic_lights.controller=actuated", _EVAL)),
        Benchmark("bottleneck0", "bottleneck", OUTFLOW, 1167.0, "",
                  (*_bottleneck_humans(2500), _EVAL)),
        Benchmark("bottleneck1", "bottleneck", OUTFLOW, 1258.0, "",
                  (*_bottleneck_humans(2500), _EVAL)),
        Benchmark("bottleneck2", "bottleneck", OUTFLOW, 2134.0, "",
                  (*_bottleneck_humans(5000), _EVAL)),
    )
}


def select(names: Iterable[str]) -> list[Benchmark]:
    """The benchmarks named: ``all``, a family (``merge`` = merge0-2) or a benchmark's name;
    each once, in Flow's order.

    Raises:
        ConfigError: an unknown name, with a did-you-mean.
    """
    wanted: set[str] = set()
    for name in names:
        key = name.strip().lower()
        if key == "all":
            wanted.update(BENCHMARKS)
        elif key in FAMILIES:
            wanted.update(b.name for b in BENCHMARKS.values() if b.family == key)
        elif key in BENCHMARKS:
            wanted.add(key)
        else:
            raise ConfigError(unknown_name("benchmark", name, [*BENCHMARKS, *FAMILIES, "all"]))
    return [b for b in BENCHMARKS.values() if b.name in wanted]


def default_config_dir(cwd: Path | None = None) -> Path:
    """``configs/benchmarks`` under ``cwd`` if it exists, else the one beside the package
    (a source checkout).

    Raises:
        ConfigError: neither exists.
    """
    here = (cwd or Path.cwd()) / "configs" / "benchmarks"
    if here.is_dir():
        return here
    beside = Path(__file__).resolve().parents[2] / "configs" / "benchmarks"
    if beside.is_dir():
        return beside
    raise ConfigError(
        f"no benchmark configs: neither {here} nor {beside} exists; pass --configs DIR "
        "(the folder holding figureeight0.yaml ... bottleneck2.yaml)"
    )


def metric_value(metric: Metric, row: Mapping[str, Any], policy: bool = False) -> float | None:
    """The metric of one run row (``None`` if it lacks it or it is not finite)."""
    value = row.get(metric.policy_key if policy else metric.baseline_key)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if math.isfinite(value) else None
