"""Run Flow's grid0 or grid1 for N steps: the env, or SUMO alone on the same traffic.

``env``: ``TrafficLightGridBenchmarkEnv`` with seeded random switch actions, one episode as
long as the run, recording off. ``raw``: SUMO alone doing the same experiment: the same
files and start (after the env's reset), the signal states the env set at each step (from a
``record`` run) and the speed and lane-change modes the kernel gives every car that enters,
then ``simulationStep``; nothing is read. The traffic is then the env's, car for car
(:func:`replay` can check it). SUMO alone running its own light programs would hold other
traffic (grid0: 69 cars on average against the env's 62), so it would not be a fair floor
for the env.

Usage (``bench/grid_instructions.sh`` counts ``env`` and ``raw`` under callgrind)::

    .venv/bin/python bench/grid_steps.py record {grid0|grid1} STEPS [LOG.json]
    .venv/bin/python bench/grid_steps.py env {grid0|grid1} STEPS
    .venv/bin/python bench/grid_steps.py raw {grid0|grid1} STEPS [LOG.json]

``raw`` replays the first STEPS steps of a log at least that long; the log's default place is
:func:`default_log` (the temporary folder).
"""

from __future__ import annotations

import json
import sys
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.envs.base import Env
from flowrun.envs.defaults import grid_config
from flowrun.envs.factory import make_env

GRIDS = {"grid0": (3, 3), "grid1": (5, 5)}


@dataclass
class CommandLog:
    """What the env told SUMO in each step of a run, and what came of it.

    Attributes:
        lights: per step, the ``(light, state)`` pairs set before the simulation step.
        modes: per vehicle type, the (speed mode, lane-change mode) given to entering cars.
        counts: per step, the number of cars after the simulation step.
    """

    lights: list[list[tuple[str, str]]]
    modes: dict[str, tuple[int, int]]
    counts: list[int]


def default_log(name: str) -> Path:
    """Where ``record`` writes and ``raw`` reads the command log of grid ``name``."""
    return Path(tempfile.gettempdir()) / f"flowrun-bench-{name}-commands.json"


def save_log(log: CommandLog, path: Path) -> None:
    """Write a command log as JSON."""
    path.write_text(json.dumps(asdict(log)))


def load_log(path: Path, steps: int) -> CommandLog:
    """Read a command log of at least ``steps`` steps (exits with a message otherwise)."""
    if not path.exists():
        sys.exit(f"no command log {path}: run bench/grid_steps.py record first")
    data = json.loads(path.read_text())
    log = CommandLog(
        [[(n, s) for n, s in step] for step in data["lights"]],
        {k: (int(a), int(b)) for k, (a, b) in data["modes"].items()},
        [int(c) for c in data["counts"]],
    )
    if len(log.lights) < steps:
        sys.exit(f"{path} logs {len(log.lights)} steps, fewer than {steps}: record more")
    return log


def make_grid_env(name: str, steps: int) -> Env:
    """The grid benchmark env with one episode at least ``steps`` long, reset with seed 0."""
    config = grid_config(*GRIDS[name])
    config.env.horizon = max(config.env.horizon, steps)  # one episode (Flow's 400 < 600)
    env = make_env(config)
    env.reset(seed=0)
    return env


def actions(env: Env, steps: int) -> list[np.ndarray]:
    """The seeded random switch actions of a run."""
    rng = np.random.default_rng(0)
    n = env.action_space.shape[0]  # type: ignore[index]
    return [rng.uniform(-1, 1, n).astype(np.float32) for _ in range(steps)]


def record(name: str, steps: int) -> CommandLog:
    """Run the env ``steps`` steps and log the commands that shape its traffic."""
    env = make_grid_env(name, steps)
    tk = env.k.traffic_light
    now: list[tuple[str, str]] = []
    set_state = tk.set_state

    def logged(node: str, state: str, link_index: int | str = "all") -> None:
        assert link_index == "all"
        now.append((node, state))
        set_state(node, state, link_index)

    tk.set_state = logged  # type: ignore[method-assign, assignment]
    log = CommandLog([], {}, [])
    for c in env.k.vehicle.table.classes:
        log.modes[c.name] = (c.speed_mode, c.lane_change_mode)
    for action in actions(env, steps):
        env.step(action)
        log.lights.append(list(now))
        now.clear()
        log.counts.append(env.k.vehicle.num_vehicles)
    env.close()
    return log


def replay(api: Any, log: CommandLog, steps: int, count: bool = False) -> list[int]:
    """SUMO alone: the logged signal states, the step, the modes of the cars that entered.

    Returns:
        the number of cars after each step when ``count`` (else nothing is read).
    """
    set_state = api.trafficlight.setRedYellowGreenState
    step, departed = api.simulationStep, api.simulation.getDepartedIDList
    v = api.vehicle
    modes, counts = log.modes, []
    for lights in log.lights[:steps]:
        for node, state in lights:
            set_state(node, state)
        step()
        for vid in departed():
            speed_mode, lc_mode = modes[v.getTypeID(vid)]
            v.setSpeedMode(vid, speed_mode)
            v.setLaneChangeMode(vid, lc_mode)
        if count:
            counts.append(v.getIDCount())
    return counts


def run_grid(mode: str, name: str, steps: int, log: CommandLog | None = None) -> None:
    """``steps`` steps of grid ``name``: ``raw`` SUMO alone replaying ``log`` (by default
    the one at :func:`default_log`), or the env."""
    if mode == "raw" and log is None:
        log = load_log(default_log(name), steps)
    env = make_grid_env(name, steps)
    if mode == "raw":
        assert env.k.process is not None and log is not None
        replay(env.k.process.api, log, steps)
    else:
        for action in actions(env, steps):
            env.step(action)
    env.close()


def main() -> None:
    """Command line: mode, grid name, steps (and the log file of ``record`` / ``raw``)."""
    mode, name, steps = sys.argv[1], sys.argv[2], int(sys.argv[3])
    path = Path(sys.argv[4]) if len(sys.argv) > 4 else default_log(name)
    if mode == "record":
        save_log(record(name, steps), path)
    else:
        run_grid(mode, name, steps, load_log(path, steps) if mode == "raw" else None)


if __name__ == "__main__":
    main()
