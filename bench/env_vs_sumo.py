"""Env step of Flow's benchmarks vs SUMO alone on the same traffic.

Usage: ``.venv/bin/python bench/env_vs_sumo.py [--steps 600] [--repeats 7] [NAME ...]``
(names: any ``configs/benchmarks/NAME.yaml``, e.g. ``merge0`` or ``grid0``; ``figureeight0``
and ``bottleneck0`` by default, about 2 min).

For each benchmark config (``configs/benchmarks/NAME.yaml``): a first env run (not timed,
seeded random actions, one episode as long as the run, recording off) logs every command the
env sends SUMO between two simulation steps (``slowDown``, ``setRoute``, ``setMaxSpeed``,
``changeLane``, the modes of entering cars, cars added or removed, signal states, ...; each
with its arguments). SUMO alone then replays that log after the same reset: the logged
commands, then ``simulationStep``, and nothing is read; the number of cars after every step
must equal the env's (checked: "same traffic"). The env and the replay take turns
``repeats`` times, each from the same reset. Times are this process's CPU time
(``time.process_time``: time waiting for a core on a busy machine is not counted), µs per env
step: the median of the repeats, and "min", the ratio of the fastest runs (the least
disturbed by other work).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.envs.base import Env
from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config

CONFIGS = Path(__file__).resolve().parent.parent / "configs" / "benchmarks"
#: the SUMO domains whose writes shape the traffic, and the prefixes of their write calls
WRITES = {
    "vehicle": ("set", "slowDown", "changeLane", "add", "remove", "moveTo", "reroute"),
    "trafficlight": ("set",),
    "lane": ("set",),
    "edge": ("set",),
}
Call = tuple[str, str, tuple[Any, ...], dict[str, Any]]  # (domain, function, arguments)


def make(name: str, steps: int) -> Env:
    """The benchmark env with one episode at least ``steps`` long, reset with seed 0."""
    cfg = load_config(CONFIGS / f"{name}.yaml", [f"env.horizon={steps + 1}"])
    env = make_env(cfg)
    env.reset(seed=0)
    return env


def actions(env: Env, steps: int) -> list[np.ndarray]:
    """The seeded random actions of a run (within the action space)."""
    rng = np.random.default_rng(0)
    space = env.action_space
    low, high = np.asarray(space.low), np.asarray(space.high)  # type: ignore[attr-defined]
    return [rng.uniform(low, high).astype(np.float32) for _ in range(steps)]


@contextmanager
def logging_writes(api: Any, calls: list[Call]) -> Iterator[None]:
    """Append every write call to SUMO (``api``: libsumo) to ``calls`` while inside.

    The compiled functions are wrapped (``_libsumo.vehicle_slowDown`` is logged as
    ``vehicle.slowDown``): libsumo's Python functions call them, and the kernel binds some of
    them directly at its reset, so every write is logged once, whichever way it was made."""
    raw = api._libsumo
    undo: list[tuple[str, Any]] = []

    def wrap(attr: str, domain: str, name: str) -> None:
        real = getattr(raw, attr)

        def logged(*args: Any, **kwargs: Any) -> Any:
            calls.append((domain, name, args, kwargs))
            return real(*args, **kwargs)

        undo.append((attr, real))
        setattr(raw, attr, logged)

    for domain, prefixes in WRITES.items():
        for attr in dir(raw):
            name = attr.removeprefix(f"{domain}_")
            if name != attr and name.startswith(prefixes):
                wrap(attr, domain, name)
    try:
        yield
    finally:
        for attr, real in reversed(undo):
            setattr(raw, attr, real)


def record(name: str, steps: int) -> tuple[list[list[Call]], list[int]]:
    """Run the env ``steps`` steps; the writes before each simulation step and the number of
    cars after it."""
    cfg = load_config(CONFIGS / f"{name}.yaml", [f"env.horizon={steps + 1}"])
    import libsumo  # the env's simulator, patched for this run only

    calls: list[Call] = []
    with logging_writes(libsumo, calls):
        env = make_env(cfg)
        env.reset(seed=0)
        assert env.k.process is not None
        api = env.k.process.api
        log: list[list[Call]] = []
        counts: list[int] = []
        sim = env.k.simulation
        assert sim._fast is not None
        real_step = sim._fast.sim_step

        def step(t: float = 0.0) -> object:  # one log entry per simulation step
            log.append(list(calls))
            calls.clear()
            result = real_step(t)
            counts.append(api.vehicle.getIDCount())
            return result

        sim._fast = replace(sim._fast, sim_step=step)
        calls.clear()  # the reset's own writes are the replay's too (it resets the same way)
        todo = actions(env, steps)
        for action in todo:
            env.step(action)
        env.close()
    return log, counts


def replay(api: Any, log: list[list[Call]], count: bool = False) -> list[int]:
    """SUMO alone: each simulation step's logged writes, then the step (nothing is read
    unless ``count``: the number of cars after each step)."""
    bound: dict[tuple[str, str], Callable[..., Any]] = {}
    for calls in log:
        for domain, name, _, _ in calls:
            bound.setdefault((domain, name), getattr(getattr(api, domain), name))
    step, counts = api.simulationStep, []
    for calls in log:
        for domain, name, args, kwargs in calls:
            bound[domain, name](*args, **kwargs)
        step()
        if count:
            counts.append(api.vehicle.getIDCount())
    return counts


def env_us(name: str, steps: int) -> float:
    """CPU µs per env step over one episode of ``steps`` steps."""
    env = make(name, steps)
    todo = actions(env, steps)
    t0 = time.process_time()
    for action in todo:
        env.step(action)
    elapsed = time.process_time() - t0
    env.close()
    return elapsed / steps * 1e6


def raw_us(name: str, steps: int, log: list[list[Call]]) -> float:
    """CPU µs per env step of SUMO alone replaying the env's writes."""
    env = make(name, steps)
    assert env.k.process is not None
    api = env.k.process.api
    t0 = time.process_time()
    replay(api, log)
    elapsed = time.process_time() - t0
    env.close()
    return elapsed / steps * 1e6


@dataclass
class Comparison:
    """The env against SUMO alone on one benchmark's traffic (CPU µs per env step).

    Attributes:
        runs: per repetition, the env's and the replay's µs per step.
        cars: the mean number of cars after a step.
        writes: the mean number of writes to SUMO per step.
        same: whether the replay held the env's number of cars after every step.
    """

    runs: list[tuple[float, float]]
    cars: float
    writes: float
    same: bool

    @property
    def env(self) -> float:
        """The env's median µs per step."""
        return statistics.median(r[0] for r in self.runs)

    @property
    def sumo(self) -> float:
        """SUMO alone's median µs per step."""
        return statistics.median(r[1] for r in self.runs)

    @property
    def ratio(self) -> float:
        """Env over SUMO alone, of the medians."""
        return self.env / self.sumo

    @property
    def fastest(self) -> float:
        """Env over SUMO alone, of the fastest runs (the least disturbed by other work)."""
        return min(r[0] for r in self.runs) / min(r[1] for r in self.runs)


def compare(name: str, steps: int, repeats: int) -> Comparison:
    """Log the env's writes, check the replay's traffic, then time both ``repeats`` times."""
    log, counts = record(name, steps)
    env = make(name, steps)
    assert env.k.process is not None
    same = replay(env.k.process.api, log, count=True) == counts
    env.close()
    runs = [(env_us(name, steps), raw_us(name, steps, log)) for _ in range(repeats)]
    writes = sum(len(c) for c in log) / steps
    return Comparison(runs, sum(counts) / len(counts), writes, same)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("names", nargs="*", default=["figureeight0", "bottleneck0"])
    p.add_argument("--steps", type=int, default=600, help="env steps per run")
    p.add_argument("--repeats", type=int, default=7)
    args = p.parse_args()
    print(f"load before: {os.getloadavg()[0]:.2f}")
    for name in args.names:
        c = compare(name, args.steps, args.repeats)
        print(f"{name}: env {c.env:6.0f} us/step  SUMO alone {c.sumo:6.0f} us/step  "
              f"ratio {c.ratio:5.2f}  (min {c.fastest:.2f}; runs "
              f"{', '.join(f'{a / b:.2f}' for a, b in c.runs)})  mean cars {c.cars:.0f}  "
              f"writes/step {c.writes:.1f}  same traffic: {'yes' if c.same else 'NO'}")  # fmt: skip
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
