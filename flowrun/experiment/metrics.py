"""Run metrics as pure functions of the per-step statistics (the same ones the log holds)."""

from __future__ import annotations

import math
from array import array
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from flowrun.envs.frames import StatsBatch


@dataclass(frozen=True)
class RunMetrics:
    """What one run measured. Speeds in m/s, times in s.

    Attributes:
        run: run index.
        steps: simulation steps logged (initial state and warm-up included).
        duration: simulated time at the last step (SUMO starts at 0), s.
        mean_speed: mean over steps of the mean speed of all vehicles (steps without vehicles
            left out; ``nan``, written ``null``, when no step had any).
        speed_std: mean over steps of the speed standard deviation across vehicles.
        min_speed: lowest speed of any vehicle at any step.
        max_speed: highest speed of any vehicle at any step.
        last_half_mean_speed: ``mean_speed`` over the second half of the steps.
        last_half_speed_std: ``speed_std`` over the second half of the steps.
        episode_return: sum of the RL-step rewards.
        collisions: collisions SUMO reported.
        teleports: teleports SUMO started.
        departed: vehicles that entered the network during the run (inflows; the cars placed
            at the start are not counted).
        arrived: vehicles that left the network during the run.
        lane_changes: lane changes of all cars during the run (same edge, another lane; 0 on
            single-lane networks).
    """

    run: int
    steps: int
    duration: float
    mean_speed: float
    speed_std: float
    min_speed: float
    max_speed: float
    last_half_mean_speed: float
    last_half_speed_std: float
    episode_return: float
    collisions: int
    teleports: int
    departed: int = 0
    arrived: int = 0
    lane_changes: int = 0

    def to_dict(self) -> dict[str, Any]:
        """Plain dict for ``metrics.json``."""
        return asdict(self)


class RunAccumulator:
    """Folds per-step statistics into :class:`RunMetrics` with constant memory per step.

    Only two doubles per step are kept (mean speed and speed std, for the last-half numbers),
    so a 100,000-step run costs 1.6 MB, not a list of objects.
    """

    def __init__(self) -> None:
        self.steps = 0
        self.time = 0.0
        self.mean = array("d")
        self.std = array("d")
        self.min_speed = math.inf
        self.max_speed = -math.inf
        self.collisions = 0
        self.teleports = 0
        self.departed = 0
        self.arrived = 0
        self.lane_changes = 0

    def add_batch(self, batch: StatsBatch) -> None:
        """Fold in the statistics of consecutive steps."""
        if not len(batch):
            return
        self.steps += len(batch)
        self.time = float(batch.time[-1])
        self.mean.extend(batch.mean_speed.tolist())
        self.std.extend(batch.speed_std.tolist())
        self.min_speed = min(self.min_speed, float(np.fmin.reduce(batch.min_speed)))
        self.max_speed = max(self.max_speed, float(np.fmax.reduce(batch.max_speed)))
        self.collisions += int(batch.collisions.sum())
        self.teleports += int(batch.teleports.sum())
        self.departed += int(batch.departed.sum())
        self.arrived += int(batch.arrived.sum())
        self.lane_changes += int(batch.lane_changes.sum())

    def result(self, run: int, episode_return: float) -> RunMetrics:
        """The metrics of everything added so far."""
        if not self.steps:
            nan = math.nan
            return RunMetrics(run, 0, 0.0, nan, nan, nan, nan, nan, nan, episode_return, 0, 0)
        mean = np.frombuffer(self.mean, dtype=np.float64)
        std = np.frombuffer(self.std, dtype=np.float64)
        half = self.steps // 2
        return RunMetrics(
            run=run,
            steps=self.steps,
            duration=float(self.time),
            mean_speed=_mean_of_occupied(mean),
            speed_std=_mean_of_occupied(std),
            min_speed=float(self.min_speed) if math.isfinite(self.min_speed) else math.nan,
            max_speed=float(self.max_speed) if math.isfinite(self.max_speed) else math.nan,
            last_half_mean_speed=_mean_of_occupied(mean[half:]),
            last_half_speed_std=_mean_of_occupied(std[half:]),
            episode_return=float(episode_return),
            collisions=self.collisions,
            teleports=self.teleports,
            departed=self.departed,
            arrived=self.arrived,
            lane_changes=self.lane_changes,
        )


def _mean_of_occupied(values: np.ndarray) -> float:
    """Mean over the steps that had vehicles (a step without any is ``nan``); ``nan`` if none.

    ``metrics.json`` writes ``nan`` as ``null``.
    """
    occupied = values[~np.isnan(values)]
    return float(np.mean(occupied)) if occupied.size else math.nan
