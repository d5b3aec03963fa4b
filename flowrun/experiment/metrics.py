"""Run metrics as pure functions of the per-step statistics (the same ones the log holds)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from flowrun.recording.frames import StepStats


@dataclass(frozen=True)
class RunMetrics:
    """What one run measured. Speeds in m/s, times in s.

    Attributes:
        run: run index.
        steps: simulation steps logged (initial state and warm-up included).
        duration: simulated time at the last step (SUMO starts at 0), s.
        mean_speed: mean over steps of the mean speed of all vehicles.
        speed_std: mean over steps of the speed standard deviation across vehicles.
        min_speed: lowest speed of any vehicle at any step.
        max_speed: highest speed of any vehicle at any step.
        last_half_mean_speed: ``mean_speed`` over the second half of the steps.
        last_half_speed_std: ``speed_std`` over the second half of the steps.
        episode_return: sum of the RL-step rewards.
        collisions: collisions SUMO reported.
        teleports: teleports SUMO started.
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

    def to_dict(self) -> dict[str, Any]:
        """Plain dict for ``metrics.json``."""
        return asdict(self)


def summarize_run(run: int, stats: Sequence[StepStats], episode_return: float) -> RunMetrics:
    """Metrics of one run from its per-step statistics."""
    if not stats:
        nan = math.nan
        return RunMetrics(run, 0, 0.0, nan, nan, nan, nan, nan, nan, episode_return, 0, 0)
    mean = np.array([s.mean_speed for s in stats])
    std = np.array([s.speed_std for s in stats])
    half = len(stats) // 2
    return RunMetrics(
        run=run,
        steps=len(stats),
        duration=float(stats[-1].time),
        mean_speed=float(np.mean(mean)),
        speed_std=float(np.mean(std)),
        min_speed=float(min(s.min_speed for s in stats)),
        max_speed=float(max(s.max_speed for s in stats)),
        last_half_mean_speed=float(np.mean(mean[half:])),
        last_half_speed_std=float(np.mean(std[half:])),
        episode_return=float(episode_return),
        collisions=int(sum(s.collisions for s in stats)),
        teleports=int(sum(s.teleports for s in stats)),
    )
