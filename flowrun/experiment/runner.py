"""``Experiment``: roll an environment out for N runs (Flow's ``flow.core.experiment``)."""

from __future__ import annotations

import logging
import math
from array import array
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.envs.base import Env
from flowrun.envs.frames import batch_stats
from flowrun.errors import ConfigError
from flowrun.experiment.metrics import RunAccumulator, RunMetrics
from flowrun.multiagent.joint import joint_view
from flowrun.recording.frames import SignalFrame, StepStats, VehicleFrame

log = logging.getLogger(__name__)


class FrameSink(Protocol):
    """Where a run's frames go (an MCAP recorder): ``write`` then ``close``."""

    def write(
        self, frame: VehicleFrame, stats: StepStats, signals: SignalFrame | None = None
    ) -> object:
        """Store one step (``signals``: only passed on networks with traffic lights)."""

    def close(self) -> None:
        """Finish the file (idempotent)."""


#: Steps queued before their statistics are computed (in one numpy batch) and logged: a hard
#: kill loses at most these beyond the recorder's last flush; Ctrl-C/SIGTERM lose nothing.
DRAIN_EVERY = 256
#: ... or fewer on big networks: at most this many vehicle-steps are queued (memory stays
#: small; with thousands of cars each step is a big enough batch on its own).
DRAIN_VEHICLE_STEPS = 1 << 14


class RunHooks(Protocol):
    """Code that runs with every run (a signal controller and its measurements)."""

    def on_reset(self, env: Env) -> None:
        """After ``env.reset``."""

    def before_step(self, env: Env) -> None:
        """Before each ``env.step``."""

    def after_step(self, env: Env) -> None:
        """After each ``env.step``."""

    def on_run_end(self, env: Env, run: int) -> None:
        """After the run's last step (also when interrupted)."""


SinkFactory = Callable[[int], FrameSink | None]
Progress = Callable[[int, int], None]


class Experiment:
    """Runs an environment without learning (Flow's ``flow.core.experiment.Experiment``).

    Args:
        env: the environment (any :class:`flowrun.envs.Env`), as in Flow's tutorial, or Flow's
            ``flow_params`` dict (``exp_tag, env_name, network, simulator, sim, env, net, veh,
            initial, tls``), from which the environment is built.
        sink_factory: called with the run index, returns where to record that run (or None).
            A dict here is taken as ``custom_callables`` (Flow's positional second argument).
        progress: called as ``progress(run, step)`` after every step.
        custom_callables: Flow's ``{name: f(env)}``: each is called after every step and the
            mean of its values per run is returned under ``name``.
        hooks: called after each reset, around each step and at the end of each run.

    Attributes:
        env: the environment.
        config: the experiment as an :class:`ExperimentConfig` when built from ``flow_params``.
    """

    def __init__(
        self,
        env: Env | Mapping[str, Any],
        sink_factory: SinkFactory | Mapping[str, Callable[[Env], Any]] | None = None,
        progress: Progress | None = None,
        custom_callables: Mapping[str, Callable[[Env], Any]] | None = None,
        hooks: RunHooks | None = None,
    ) -> None:
        if isinstance(sink_factory, Mapping):  # Flow's ``Experiment(flow_params, callables)``
            sink_factory, custom_callables = None, sink_factory
        self.config: ExperimentConfig | None = None
        if isinstance(env, Mapping):
            from flowrun.envs.flow_params import make_flow_env
            from flowrun.loading.flow_params import from_flow_params

            flow = from_flow_params(env)
            self.config = flow.config
            env = make_flow_env(flow)
        self.env = env
        self.sink_factory = sink_factory
        self.progress = progress
        self.custom_callables = dict(custom_callables or {})
        self.hooks = hooks
        self.metrics: list[RunMetrics] = []
        self.csv_files: list[Path] = []

    def run(
        self,
        num_runs: int,
        num_steps: int | Callable[[Any], Any] | None = None,
        rl_actions: Callable[[Any], Any] | None = None,
        convert_to_csv: bool = False,
        seed: int | None = None,
    ) -> dict[str, Any]:
        """Run ``num_runs`` episodes of at most ``num_steps`` steps each.

        Args:
            num_runs: number of runs (each starts with ``env.reset``).
            num_steps: steps per run (a run also ends at a collision or the horizon);
                ``None`` means ``env_params.horizon``, as Flow's ``run(num_runs)``. A callable
                here is taken as ``rl_actions`` (Flow's ``run(num_runs, rl_actions)``).
            rl_actions: maps an observation to an action; ``None`` sends no RL action.
            convert_to_csv: write run ``i``'s vehicle states to Flow's
                ``<emission_path>/<network name>-<i>_emission.csv`` with Flow's columns (from
                its MCAP log: the run's own log when recording, else a log in a new folder
                under ``sim_params.emission_path``). Paths in ``csv_files``.
            seed: run ``i`` resets with seed ``seed + i``; ``None`` continues the env's
                generator (first reset seeded by ``sim.seed``).

        Returns:
            Flow's ``info_dict``: ``returns``, ``mean_returns``, ``per_step_returns``,
            ``velocities`` (mean speed of each run), ``mean_velocities``, ``outflows``
            (veh/h over the last 500 s of each run), ``mean_outflows``, one list per custom
            callable, plus ``metrics`` (one :class:`RunMetrics` per run).

        Raises:
            ConfigError: no ``num_steps`` and an infinite horizon, or ``convert_to_csv``
                without anywhere to write.
        """
        if callable(num_steps):
            num_steps, rl_actions = None, num_steps
        steps = self._steps(num_steps)
        env = joint_view(self.env)  # a multi-agent env: joint dicts, mean reward, its end
        sink_factory = self.sink_factory
        if convert_to_csv and sink_factory is None:
            sink_factory = self._csv_sinks()
        env.collect_stats = True
        self.metrics = []
        self.csv_files = []
        env.record_frames = sink_factory is not None
        runs: list[_Run] = []
        for run in range(num_runs):
            done = _Run(run, self.custom_callables)
            self._one_run(env, done, steps, rl_actions, seed, sink_factory)
            done.outflow = _outflow(env)
            runs.append(done)
            log.info("run %d: return %.3f", run, done.ret)
            if convert_to_csv and done.sink is not None:
                self._export(done.sink, run)
        return _info_dict(runs, list(self.custom_callables), self.metrics)

    def _one_run(self, env: Any, done: _Run, steps: int, rl_actions: Callable[[Any], Any] | None,
                 seed: int | None, sink_factory: SinkFactory | None) -> None:  # fmt: skip
        """Reset, step to the run's end and record into ``done``; the queued steps are
        written, the sink closed, the metrics kept and ``on_run_end`` called also when
        interrupted (not when the reset failed)."""
        started = False
        try:
            obs, _ = env.reset(seed=None if seed is None else seed + done.run)
            started = True
            done.sink = sink_factory(done.run) if sink_factory else None
            if self.hooks is not None:
                self.hooks.on_reset(env)
            # The state after reset goes to the log at once (the recorder flushes its first
            # frame): a run killed before the first batch still leaves a readable log.
            self._drain(done.sink, done.stats)
            self._step_to_end(env, done, obs, steps, rl_actions)
        finally:
            try:
                self._drain(done.sink, done.stats)  # also when interrupted: every step logged
            finally:
                if done.sink is not None:
                    done.sink.close()
                if started:
                    self.metrics.append(done.stats.result(done.run, done.ret))
                    if self.hooks is not None:
                        self.hooks.on_run_end(env, done.run)

    def _step_to_end(self, env: Any, done: _Run, obs: Any, steps: int,
                     rl_actions: Callable[[Any], Any] | None) -> None:  # fmt: skip
        """Step until ``steps``, a collision or the horizon; queued steps are written in
        batches (fewer steps per batch on networks with many cars)."""
        hooks, rewards, ret = self.hooks, done.rewards, 0.0  # locals: the loop runs per step
        vehicles = max(env.k.vehicle.num_vehicles, 1)
        drain_at = max(1, min(DRAIN_EVERY, DRAIN_VEHICLE_STEPS // vehicles))
        try:
            for step in range(steps):
                action = rl_actions(obs) if rl_actions is not None else None
                if hooks is not None:
                    hooks.before_step(env)
                obs, reward, terminated, truncated, _ = env.step(action)
                if hooks is not None:
                    hooks.after_step(env)
                ret += reward
                rewards.append(reward)
                for key, fn in self.custom_callables.items():
                    done.values[key].append(fn(env))
                if len(env.records) >= drain_at:
                    self._drain(done.sink, done.stats)
                if self.progress is not None:
                    self.progress(done.run, step + 1)
                if terminated or truncated:
                    break
        finally:
            done.ret = ret

    def _steps(self, num_steps: int | None) -> int:
        if num_steps is not None:
            return int(num_steps)
        horizon = self.env.env_params.horizon
        if math.isinf(horizon):
            raise ConfigError(
                "EnvParams.horizon is infinite, so a run would never end; set "
                "EnvParams(horizon=...) or pass num_steps",
                path="env.horizon",
            )
        return int(horizon)

    def _csv_sinks(self) -> SinkFactory:
        from flowrun.experiment.emission import emission_dir, run_recorder

        name = self.config.name if self.config is not None else self.env.network.name
        folder = emission_dir(self.env, name)
        return lambda run: run_recorder(folder, self.env, run, self.config)

    def _export(self, sink: FrameSink, run: int) -> None:
        from flowrun.experiment.emission import flow_emission_csv, flow_emission_path

        path = getattr(sink, "path", None)
        if isinstance(path, Path) and path.suffix == ".mcap":
            base = self.env.sim_params.emission_path
            if base is None:  # a sink of the caller's own: emission_dir did not check
                raise ConfigError(
                    "convert_to_csv=True writes Flow's <network>-<run>_emission.csv files into "
                    "SumoParams(emission_path=...); set it (YAML: sim.emission_path)",
                    path="sim.emission_path",
                )
            out = flow_emission_path(base, self.env.network.name, run)
            flow_emission_csv(path, out, self.env.sim_params.sim_step)
            self.csv_files.append(out)

    def _drain(self, sink: FrameSink | None, stats: RunAccumulator) -> None:
        """Aggregate the queued steps in one batch, fold them in, and write their frames."""
        if not self.env.records:
            return
        records = self.env.take_records()
        batch = batch_stats(records)
        stats.add_batch(batch)
        if sink is not None:
            for record, step_stats in zip(records, batch.rows(), strict=True):
                if record.frame is None:
                    continue
                if record.signals is None:
                    sink.write(record.frame, step_stats)
                else:
                    sink.write(record.frame, step_stats, record.signals)


class _Run:
    """What one run produced so far: its sink, statistics, return, rewards per step, the
    custom callables' values and (at its end) its outflow, veh/h."""

    def __init__(self, run: int, custom_callables: Mapping[str, Any]) -> None:
        self.run = run
        self.sink: FrameSink | None = None
        self.stats = RunAccumulator()
        self.ret = 0.0
        self.rewards = array("d")  # 8 bytes a step: memory stays flat over long runs
        self.values: dict[str, list[Any]] = {key: [] for key in custom_callables}
        self.outflow = 0.0


def _info_dict(runs: list[_Run], custom: list[str], metrics: list[RunMetrics]) -> dict[str, Any]:
    """Flow's ``info_dict`` of the runs (see :meth:`Experiment.run`)."""
    returns = [r.ret for r in runs]
    velocities = [m.mean_speed for m in metrics]
    outflows = [r.outflow for r in runs]
    means = {key: [_mean_or_nan(r.values[key]) for r in runs] for key in custom}
    return {
        "returns": returns,
        "mean_returns": _mean(returns),
        "per_step_returns": [r.rewards.tolist() for r in runs],
        "velocities": velocities,
        "mean_velocities": _mean(velocities),
        "outflows": outflows,
        "mean_outflows": _mean(outflows),
        **means,
        "metrics": list(metrics),
    }


def _mean_or_nan(values: list[Any]) -> float:
    return float(np.mean(values)) if values else float("nan")


def _mean(values: list[float]) -> float:
    return float(np.mean(values)) if values else 0.0


def _outflow(env: Env) -> float:
    """Vehicles that left the network over the last 500 s, per hour (Flow's ``outflows``)."""
    rate = getattr(env.k.vehicle, "get_outflow_rate", None)
    return float(rate(500)) if rate is not None else 0.0
