"""Hand-written policies on bottleneck0, grid0 and figureeight0: are the targets reachable by
the envs' controls?

Run: ``.venv/bin/python bench/hand_policies.py bottleneck0|grid0|figureeight0 [--seeds 5]
[--wide]``
(a few minutes per benchmark; ``--wide`` tries more parameters).

Each policy is a function of the env's state fed through the env's own action space (the env is
not changed) and is scored as ``flowrun benchmark`` scores a trained policy: the benchmark
config in evaluate mode, one episode per evaluation seed (1000000, 1000001, ...), the metric
being the episode's return. The benchmark's own baseline runs on the same seeds.

* bottleneck0 (``BottleneckDesiredVelocityEnv``): an action moves the speed cap of the AVs in
  each controlled cell (edge segment x lane) by at most 1.5 m/s a step. ``cap v @ E`` holds the
  slowest-capped AV of every cell of edges ``E`` at ``v`` m/s (each step's change is
  ``v - its cap``, clipped to the action space) and releases the AVs elsewhere (+1.5 m/s a
  step up to the 23 m/s speed limit); ``meter v @ E if n > N`` does so only while more than
  ``N`` cars are on the 2-lane edge 4 (the mean over the last 10 steps), else releases
  (``until n <= M``: once on, until at most ``M`` cars are there).
  ``--capacity`` adds the all-human outflow at inflows 1,500-2,500 veh/h (the baseline's
  set-up, the metric's window).
* grid0 (``TrafficLightGridBenchmarkEnv``): an action > 0 switches a light through 3 s of
  yellow. ``program`` never switches (the network's own fixed program runs); ``fixed k``
  switches every light every ``k`` s (``+o``: light at row r, column c ``o * (r + c)`` s
  later, a green wave); ``queue D g`` switches a light once its green has lasted ``g`` s
  (after its yellow) and more cars are within ``D`` m of it on its red approaches than on its
  green ones. Every policy but ``program`` switches all lights at the first step to take them over.
* figureeight0 (``AccelEnv``): the AV's acceleration from what the env observes; the rules,
  their scoring (the whole episode's mean speed, its second half and first 30 s) and the
  column ceiling are in ``bench/hand_figure_eight.py``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.envs.factory import make_env
from flowrun.experiment.benchmark import BENCHMARKS
from flowrun.experiment.benchmark_results import TARGETS, eval_seeds
from flowrun.experiment.runner import Experiment
from flowrun.loading.loader import load_config

sys.path.insert(0, str(Path(__file__).resolve().parent))
import hand_figure_eight

CONFIGS = Path(__file__).resolve().parent.parent / "configs" / "benchmarks"
#: a policy: built for an env, then called with each observation
Policy = Callable[[Any], Callable[[Any], Any] | None]


# ---------------------------------------------------------------- pure rules (tested)
def cap_deltas(min_caps: np.ndarray, targets: np.ndarray, low: float, high: float) -> np.ndarray:
    """Bottleneck action: per controlled cell, the change that brings the cell's slowest-capped
    AV to its target cap (clipped to ``[low, high]``); ``high`` (release towards the speed
    limit) where the target is ``nan``; 0 in a targeted cell without an AV (``min_caps`` nan).
    """
    delta = np.clip(targets - min_caps, low, high)
    delta = np.where(np.isnan(min_caps), 0.0, delta)
    return np.where(np.isnan(targets), high, delta)


def meter_engaged(engaged: bool, crowd: float, on: float, off: float) -> bool:
    """Whether the bottleneck meter holds the AVs back: once ``crowd`` (cars on edge 4) is above
    ``on``, until it is at most ``off``."""
    return crowd > on or (engaged and crowd > off)


def fixed_time_switch(step: int, period: int, offsets: np.ndarray) -> np.ndarray:
    """Grid action (+1 switch, -1 hold) of a fixed-time plan: every light at the first step,
    then light ``i`` whenever ``step - offsets[i]`` is a positive multiple of ``period``."""
    late = step - offsets
    due = (step == 0) | ((late > 0) & (late % period == 0))
    return np.where(due, 1.0, -1.0)


def queue_switch(
    green: np.ndarray, red: np.ndarray, since: np.ndarray, yellow: np.ndarray, min_green: float
) -> np.ndarray:
    """Grid action (+1 switch, -1 hold) of the longest-queue rule: switch a light that is not
    yellow, for which ``since`` (seconds since its last switch began) is at least ``min_green``
    and that has more cars waiting on red than coming on green.
    """
    due = (yellow == 0) & (since >= min_green) & (red > green)
    return np.where(due, 1.0, -1.0)


# ---------------------------------------------------------------- bottleneck0
def _min_caps(env: Any) -> np.ndarray:
    """The lowest speed cap of the AVs in each controlled cell (nan: no AV), cells numbered
    as the env numbers its actions."""
    vk = env.k.vehicle
    caps = np.full(env.action_space.shape[0], np.nan)
    for rl_id in vk.get_rl_ids():
        edge = vk.get_edge(rl_id)
        if edge not in env.action_index:
            continue
        slices = env.slices[edge]
        seg = int(np.searchsorted(slices, vk.get_position(rl_id), side="right")) - 1
        seg = min(max(seg, 0), len(slices) - 2)
        i = env.action_index[edge] + seg * env.k.network.num_lanes(edge) + vk.get_lane(rl_id)
        caps[i] = np.fmin(caps[i], vk.get_max_speed(rl_id))
    return caps


def _zone_targets(env: Any, edges: str, speed: float) -> np.ndarray:
    """``speed`` on every controlled cell of the edges named (``"23"``: edges 2 and 3), nan
    elsewhere."""
    targets = np.full(env.action_space.shape[0], np.nan)
    for edge, start in env.action_index.items():
        if edge in edges:
            n = int(dict((str(e), int(k)) for e, k, _ in env.segments)[edge])
            targets[start : start + n * env.k.network.num_lanes(edge)] = speed
    return targets


def cap_policy(
    edges: str, speed: float, crowd: float | None = None, release: float | None = None
) -> Policy:
    """``cap v @ E`` (always) or ``meter v @ E if n > N`` (``crowd`` = N; with ``release`` =
    M, ``... until n <= M``)."""

    def build(env: Any) -> Callable[[Any], Any]:
        space = env.action_space
        on = _zone_targets(env, edges, speed)
        off = np.full_like(on, np.nan)
        engaged = [crowd is None]

        def act(_obs: Any) -> Any:
            if crowd is not None:
                n = float(np.mean(env.smoothed_num))
                engaged[0] = meter_engaged(
                    engaged[0], n, crowd, crowd if release is None else release
                )
            return cap_deltas(
                _min_caps(env), on if engaged[0] else off, space.low[0], space.high[0]
            )

        return act

    return build


def bottleneck_policies(wide: bool) -> dict[str, Policy]:
    speeds = (3.0, 5.0, 7.0, 10.0, 14.0, 18.0) if wide else (5.0, 10.0)
    zones = ("2", "3", "4", "23", "234") if wide else ("23", "4")
    out: dict[str, Policy] = {"AVs uncapped (cap 23 m/s)": cap_policy("", 23.0)}
    for zone in zones:
        for v in speeds:
            out[f"cap {v:g} @ {'+'.join(zone)}"] = cap_policy(zone, v)
    meters = [("23", v, n) for v in (0.01, 0.5, 1.0, 2.0, 3.0) for n in (8, 10, 12, 14, 16)]
    meters += [(zone, 1.0, n) for zone in ("2", "3") for n in (10, 12)]
    if not wide:
        meters = [("23", 0.01, 12), ("23", 0.5, 12), ("23", 2.0, 10)]
        meters += [("23", 1.0, n) for n in (10, 11, 12, 13, 14)]
    for zone, v, n in meters:
        out[f"meter {v:g} @ {'+'.join(zone)} if n > {n}"] = cap_policy(zone, v, crowd=n)
    for v, n, m in ((1.0, 12, 8), (1.0, 12, 6), (1.0, 10, 6), (1.0, 14, 8), (0.5, 12, 8)) * wide:
        out[f"meter {v:g} @ 2+3 if n > {n} until n <= {m}"] = cap_policy("23", v, n, release=m)
    if wide:
        out["meter 0.01 @ 2+3+4 if n > 10"] = cap_policy("234", 0.01, crowd=10)
    return out


def capacity_rows(seeds: Sequence[int], inflows: Sequence[int]) -> list[Row]:
    """The all-human bottleneck0 (the benchmark's baseline) at other inflows."""
    base = BENCHMARKS["bottleneck0"].baseline
    return [_scores("bottleneck0", [*base, f"network.inflows.0.vehs_per_hour={q}"], None, seeds,
                    f"all human, {q:,} veh/h in") for q in inflows]  # fmt: skip


# ---------------------------------------------------------------- grid0
def _offsets(env: Any, wave: float) -> np.ndarray:
    return np.array([wave * (i // env.cols + i % env.cols) for i in range(len(env.light_ids))])


def fixed_policy(period: int, wave: float = 0.0) -> Policy:
    def build(env: Any) -> Callable[[Any], Any]:
        offsets, step = _offsets(env, wave), [0]

        def act(_obs: Any) -> Any:
            step[0] += 1
            return fixed_time_switch(step[0] - 1, period, offsets)

        return act

    return build


def _approach_counts(env: Any, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Per light, the cars within ``reach`` m of it on its vertical and horizontal approaches."""
    vk, net = env.k.vehicle, env.k.network
    near: dict[str, int] = {}
    for edge, pos in zip(vk.edges, np.asarray(vk.lane_pos, dtype=float), strict=True):
        if edge and not edge.startswith(":") and net.edge_length(edge) - pos <= reach:
            near[edge] = near.get(edge, 0) + 1
    vert, horiz = np.zeros(len(env.node_mapping)), np.zeros(len(env.node_mapping))
    for i, (_, edges) in enumerate(env.node_mapping):
        for edge in edges:
            is_vertical = edge.rstrip("0123456789_").startswith(("left", "right"))
            (vert if is_vertical else horiz)[i] += near.get(edge, 0)
    return vert, horiz


def queue_policy(reach: float, min_green: float) -> Policy:
    def build(env: Any) -> Callable[[Any], Any]:
        n = len(env.light_ids)
        since = np.full(n, np.inf)  # s since each light's last switch (the env counts only yellow)

        def act(_obs: Any) -> Any:
            if np.isinf(since[0]):  # the first step: take the lights over
                since[:] = 0.0
                return np.ones(n)
            since[:] += env.sim_step
            vert, horiz = _approach_counts(env, reach)
            t = env.timers  # direction 0: vertical green
            green = np.where(t.direction == 0, vert, horiz)
            red = np.where(t.direction == 0, horiz, vert)
            out = queue_switch(
                green, red, since, t.currently_yellow, env.min_switch_time + min_green
            )
            since[out > 0] = 0.0
            return out

        return act

    return build


def grid_policies(wide: bool) -> dict[str, Policy]:
    out: dict[str, Policy] = {"program (never switch)": lambda env: lambda _o: -np.ones(9)}
    periods = (8, 10, 12, 15, 20, 25, 30, 40, 50) if wide else (8, 10, 20, 40)
    waves = ((20, 5.0), (20, 10.0), (30, 5.0), (30, 10.0), (40, 10.0)) if wide else ((20, 10.0),)
    for k in periods:
        out[f"fixed {k}"] = fixed_policy(k)
    for k, o in waves:
        out[f"fixed {k} +{o:g}"] = fixed_policy(k, o)
    for reach in (50.0, 100.0, 200.0) if wide else (100.0, 200.0):
        for g in (4.0, 8.0, 12.0) if wide else (4.0, 8.0):
            out[f"queue {reach:g} m, {g:g} s"] = queue_policy(reach, g)
    return out


# ---------------------------------------------------------------- running and printing
@dataclass(frozen=True)
class Row:
    """A policy's episodes: the metric, cars in and out, teleports and collisions per seed."""

    label: str
    values: list[float]
    departed: list[int]
    arrived: list[int]
    teleports: list[int]

    @property
    def mean(self) -> float:
        return statistics.mean(self.values)


def _scores(name: str, sets: Sequence[str], policy: Policy | None, seeds: Sequence[int],
            label: str) -> Row:  # fmt: skip
    """The evaluate-mode return of each seed's episode (``policy`` None: no action)."""
    cfg = load_config(CONFIGS / f"{name}.yaml", [*sets, "env.evaluate=true"])
    env = make_env(cfg)
    try:
        experiment, runs = Experiment(env), []
        for seed in seeds:  # a new policy per episode: its closure keeps per-episode state
            act = policy(env) if policy is not None else None
            experiment.run(1, int(cfg.env.horizon), rl_actions=act, seed=seed)
            runs.append(experiment.metrics[0])
    finally:
        env.close()
    return Row(
        label,
        [float(m.episode_return) for m in runs],
        [m.departed for m in runs],
        [m.arrived for m in runs],
        [m.teleports + m.collisions for m in runs],
    )


def _table(name: str, rows: list[Row], baseline: float, target: float) -> None:
    print("| policy | per seed | mean | vs baseline | target | cars in / out | teleports |")
    print("|---|---|---:|---:|---|---:|---:|")
    for r in rows:
        gain = (r.mean - baseline) / abs(baseline) * 100
        per = ", ".join(f"{v:.1f}" if name == "grid0" else f"{v:.0f}" for v in r.values)
        fmt = f"{r.mean:.1f}" if name == "grid0" else f"{r.mean:,.0f}"
        cars = f"{statistics.mean(r.departed):.0f} / {statistics.mean(r.arrived):.0f}"
        print(
            f"| {r.label} | {per} | {fmt} | {gain:+.1f} % | {'met' if r.mean >= target else '-'}"
            f" | {cars} | {sum(r.teleports)} |"
        )


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("benchmark", choices=("bottleneck0", "grid0", "figureeight0"))
    parser.add_argument("--seeds", type=int, default=5, help="evaluation episodes (default 5)")
    parser.add_argument("--wide", action="store_true", help="more parameters per policy")
    parser.add_argument(
        "--capacity",
        action="store_true",
        help="bottleneck0: all-human outflow at inflows 1,500-2,500 veh/h",
    )
    args = parser.parse_args(argv)
    name, seeds = args.benchmark, eval_seeds()[: args.seeds]
    print(f"{name}, evaluate mode, seeds {seeds[0]}-{seeds[-1]}, load {os.getloadavg()[0]:.1f}, "
          f"`{' '.join([Path(sys.argv[0]).name, *(argv or sys.argv[1:])])}`\n")  # fmt: skip
    if name == "figureeight0":
        hand_figure_eight.main(seeds, args.wide, CONFIGS)
        return
    label = "SUMO's actuated lights" if name == "grid0" else "all human (baseline)"
    base = _scores(name, BENCHMARKS[name].baseline, None, seeds, label)
    target = TARGETS[name].threshold(base.mean)
    assert target is not None
    rows = [base]
    policies = bottleneck_policies(args.wide) if name == "bottleneck0" else grid_policies(args.wide)
    for text, policy in policies.items():
        rows.append(_scores(name, (), policy, seeds, text))
        print(f"  {text}: {rows[-1].mean:.1f}", file=sys.stderr, flush=True)
    if name == "bottleneck0" and args.capacity:
        rows += capacity_rows(seeds, (1500, 1700, 1800, 1900, 2000, 2200, 2500))
    print(f"baseline {base.mean:.1f}, target ({TARGETS[name].text}) {target:.1f}\n")
    _table(name, rows, base.mean, target)
    best = max(rows[1 : 1 + len(policies)], key=lambda r: r.mean)
    print(f"\nbest hand policy: {best.label}, {best.mean:.1f}")


if __name__ == "__main__":
    main()
