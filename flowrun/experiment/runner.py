"""``Experiment``: roll an environment out for N runs (Flow's ``flow.core.experiment``)."""

from __future__ import annotations

import logging
from array import array
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from flowrun.envs.base import Env
from flowrun.envs.frames import batch_stats
from flowrun.experiment.metrics import RunAccumulator, RunMetrics
from flowrun.recording.frames import StepStats, VehicleFrame

log = logging.getLogger(__name__)


class FrameSink(Protocol):
    """Where a run's frames go (an MCAP recorder): ``write`` then ``close``."""

    def write(self, frame: VehicleFrame, stats: StepStats) -> object:
        """Store one step."""

    def close(self) -> None:
        """Finish the file (idempotent)."""


#: Steps queued before their statistics are computed (in one numpy batch) and logged: a hard
#: kill loses at most these beyond the recorder's last flush; Ctrl-C/SIGTERM lose nothing.
DRAIN_EVERY = 256
#: ... or fewer on big networks: at most this many vehicle-steps are queued (memory stays
#: small; with thousands of cars each step is a big enough batch on its own).
DRAIN_VEHICLE_STEPS = 1 << 14

SinkFactory = Callable[[int], FrameSink | None]
Progress = Callable[[int, int], None]


class Experiment:
    """Runs an environment without learning (Flow's ``Experiment(env)``).

    Args:
        env: the environment (any :class:`flowrun.envs.Env`).
        sink_factory: called with the run index, returns where to record that run (or None).
        progress: called as ``progress(run, step)`` after every step.
    """

    def __init__(
        self,
        env: Env,
        sink_factory: SinkFactory | None = None,
        progress: Progress | None = None,
    ) -> None:
        self.env = env
        self.sink_factory = sink_factory
        self.progress = progress
        self.metrics: list[RunMetrics] = []

    def run(
        self,
        num_runs: int,
        num_steps: int,
        rl_actions: Callable[[Any], Any] | None = None,
        convert_to_csv: bool = False,
        seed: int | None = None,
    ) -> dict[str, Any]:
        """Run ``num_runs`` episodes of at most ``num_steps`` steps each.

        Args:
            num_runs: number of runs (each starts with ``env.reset``).
            num_steps: steps per run (a run also ends at a collision or the horizon).
            rl_actions: maps an observation to an action; ``None`` sends no RL action.
            convert_to_csv: accepted for Flow compatibility; use ``flowrun replay --csv``.
            seed: run ``i`` resets with seed ``seed + i``; ``None`` continues the env's
                generator (first reset seeded by ``sim.seed``).

        Returns:
            Flow's ``info_dict``: ``returns``, ``mean_returns``, ``velocities`` (mean speed of
            each run), ``mean_velocities``, ``per_step_returns``, plus ``metrics`` (one
            :class:`RunMetrics` per run).
        """
        env = self.env
        env.collect_stats = True
        returns, per_step = [], []
        self.metrics = []
        env.record_frames = self.sink_factory is not None
        for run in range(num_runs):
            sink: FrameSink | None = None
            stats = RunAccumulator()
            ret = 0.0
            rewards = array("d")  # 8 bytes a step: memory stays flat over long runs
            try:
                obs, _ = env.reset(seed=None if seed is None else seed + run)
                sink = self.sink_factory(run) if self.sink_factory else None
                vehicles = max(env.k.vehicle.num_vehicles, 1)
                drain_at = max(1, min(DRAIN_EVERY, DRAIN_VEHICLE_STEPS // vehicles))
                for step in range(num_steps):
                    action = rl_actions(obs) if rl_actions is not None else None
                    obs, reward, terminated, truncated, _ = env.step(action)
                    ret += reward
                    rewards.append(reward)
                    if len(env.records) >= drain_at:
                        self._drain(sink, stats)
                    if self.progress is not None:
                        self.progress(run, step + 1)
                    if terminated or truncated:
                        break
            finally:
                try:
                    self._drain(sink, stats)  # also when interrupted: the log keeps every step
                finally:
                    if sink is not None:
                        sink.close()
                    self.metrics.append(stats.result(run, ret))
            returns.append(ret)
            per_step.append(rewards.tolist())
        velocities = [m.mean_speed for m in self.metrics]
        return {
            "returns": returns,
            "mean_returns": float(np.mean(returns)) if returns else 0.0,
            "per_step_returns": per_step,
            "velocities": velocities,
            "mean_velocities": float(np.mean(velocities)) if velocities else 0.0,
            "metrics": list(self.metrics),
        }

    def _drain(self, sink: FrameSink | None, stats: RunAccumulator) -> None:
        """Aggregate the queued steps in one batch, fold them in, and write their frames."""
        if not self.env.records:
            return
        records = self.env.take_records()
        batch = batch_stats(records)
        stats.add_batch(batch)
        if sink is not None:
            for record, step_stats in zip(records, batch.rows(), strict=True):
                if record.frame is not None:
                    sink.write(record.frame, step_stats)
