"""Env step of Flow's figure eight and bottleneck benchmarks vs SUMO alone on the same traffic.

Usage: ``.venv/bin/python bench/env_vs_sumo.py [--steps 600] [--repeats 7] [NAME ...]``
(names: ``figureeight0``, ``bottleneck0``; both by default; about 2 min).

For each benchmark config (``configs/benchmarks/NAME.yaml``): a first env run (not timed,
seeded random actions, one episode as long as the run, recording off) logs every command the
env sends SUMO between two simulation steps (``slowDown``, ``setRoute``, ``setMaxSpeed``,
``changeLane``, the modes of entering cars, cars added or removed, ...; each with its
arguments). SUMO alone then replays that log after the same reset: the logged commands, then
``simulationStep``, and nothing is read; the number of cars after every step must equal the
env's (checked: "same traffic"). The env and the replay take turns ``repeats`` times, each
from the same reset. Times are this process's CPU time (``time.process_time``: time waiting
for a core on a busy machine is not counted), µs per env step: the median of the repeats,
and "min", the ratio of the fastest runs (the least disturbed by other work).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
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
    """Append every write call to SUMO (``api``: libsumo) to ``calls`` while inside; the
    compiled ``slowDown`` the kernel binds at its reset is logged as ``vehicle.slowDown``."""
    undo: list[tuple[Any, str, Any]] = []

    def wrap(owner: Any, attr: str, domain: str, name: str) -> None:
        real = getattr(owner, attr)

        def logged(*args: Any, **kwargs: Any) -> Any:
            calls.append((domain, name, args, kwargs))
            return real(*args, **kwargs)

        undo.append((owner, attr, real))
        setattr(owner, attr, logged)

    for domain, prefixes in WRITES.items():
        owner = getattr(api, domain)
        for name in [n for n in dir(owner) if n.startswith(prefixes)]:
            wrap(owner, name, domain, name)
    wrap(api._libsumo, "vehicle_slowDown", "vehicle", "slowDown")
    try:
        yield
    finally:
        for owner, attr, real in reversed(undo):
            setattr(owner, attr, real)


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


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("names", nargs="*", default=["figureeight0", "bottleneck0"])
    p.add_argument("--steps", type=int, default=600, help="env steps per run")
    p.add_argument("--repeats", type=int, default=7)
    args = p.parse_args()
    print(f"load before: {os.getloadavg()[0]:.2f}")
    for name in args.names:
        log, counts = record(name, args.steps)
        env = make(name, args.steps)
        assert env.k.process is not None
        same = replay(env.k.process.api, log, count=True) == counts
        env.close()
        runs = [(env_us(name, args.steps), raw_us(name, args.steps, log))
                for _ in range(args.repeats)]  # fmt: skip
        e = statistics.median(r[0] for r in runs)
        r = statistics.median(r[1] for r in runs)
        fastest = min(r[0] for r in runs) / min(r[1] for r in runs)
        writes = sum(len(c) for c in log) / args.steps
        print(f"{name}: env {e:6.0f} us/step  SUMO alone {r:6.0f} us/step  ratio {e / r:5.2f}  "
              f"(min {fastest:.2f}; runs {', '.join(f'{a / b:.2f}' for a, b in runs)})  "
              f"mean cars {sum(counts) / len(counts):.0f}  writes/step {writes:.1f}  "
              f"same traffic: {'yes' if same else 'NO'}")  # fmt: skip
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
