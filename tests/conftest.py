"""Shared fixtures: the repository's configs and a seeded SUMO rollout that keeps every step."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from flowrun.config.model import ExperimentConfig
from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


@dataclass(frozen=True)
class Trajectory:
    """Per-step kernel state of one rollout; row 0 is the state right after ``reset``.

    Attributes:
        position: ring position of every car, m, shape (steps + 1, n).
        speed: speed of every car, m/s.
        lanes: lane index of every car.
        length: ring length, m.
        dt: simulation step, s.
        collisions: collisions SUMO reported over the rollout.
        teleports: teleports SUMO reported over the rollout.
    """

    position: np.ndarray
    speed: np.ndarray
    lanes: np.ndarray
    length: float
    dt: float
    collisions: int
    teleports: int


def load(name: str, *overrides: str) -> ExperimentConfig:
    """A repository config (``configs/<name>.yaml``) with ``a.b=value`` overrides."""
    return load_config(CONFIGS / f"{name}.yaml", list(overrides))


def run(cfg: ExperimentConfig, steps: int) -> Trajectory:
    """Reset ``cfg``'s environment with its ``sim.seed`` and run ``steps`` steps, no RL action."""
    env = make_env(cfg)
    try:
        env.reset(seed=int(cfg.sim.seed or 0))
        vk = env.k.vehicle
        pos, speed, lanes = [vk.position.copy()], [vk.speed.copy()], [vk.lanes.copy()]
        for _ in range(steps):
            env.step(None)
            vk = env.k.vehicle
            pos.append(vk.position.copy())
            speed.append(vk.speed.copy())
            lanes.append(vk.lanes.copy())
        return Trajectory(
            np.array(pos),
            np.array(speed),
            np.array(lanes),
            env.k.network.length(),
            env.sim_step,
            env.k.simulation.collisions,
            env.k.simulation.teleports,
        )
    finally:
        env.close()


@pytest.fixture(scope="session")
def config() -> Callable[..., ExperimentConfig]:
    """``config("sugiyama", "vehicles[0].count=1", ...)``: see :func:`load`."""
    return load


@pytest.fixture(scope="session")
def rollout() -> Callable[[ExperimentConfig, int], Trajectory]:
    """``rollout(cfg, steps)``: see :func:`run`."""
    return run
