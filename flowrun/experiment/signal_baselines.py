"""Non-RL signal baselines on the traffic-light grid: fixed-time, SUMO's actuated, max-pressure.

The controller is the config's ``traffic_lights.controller`` (its programs are loaded by
:func:`flowrun.envs.factory.make_network`):

* ``fixed_time``: every light runs a static program, Flow's phase lengths (31 s green,
  ``yellow`` s yellow per direction).
* ``actuated``: SUMO's gap-actuated program, Flow's ``TrafficLightParams(baseline=True)``
  (31 s [8, 45] green, 6 s yellow, max gap 3 s).
* ``max_pressure``: every step a light whose green has lasted ``min_green`` s switches (through
  ``yellow`` s of yellow) when the other direction's pressure is higher; the pressure of a
  direction is the sum over its links of (cars on the incoming edge - cars on the outgoing
  edge) (Varaiya, "Max pressure control of a network of signalized junctions", 2013).

:class:`SignalRun` drives the controller and measures a run through the hooks of
:class:`~flowrun.experiment.runner.Experiment` (what ``flowrun baseline`` uses);
:func:`run_signal_baseline` runs one controller on a grid experiment and returns the metrics.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.config.params import EnvParams
from flowrun.config.signal_control import CONTROLLERS, TrafficLightsConfig
from flowrun.config.signal_control import controller_programs as signal_program
from flowrun.envs.base import Env
from flowrun.envs.factory import make_network
from flowrun.envs.signals import SwitchTimers, phase_state
from flowrun.envs.test import TestEnv
from flowrun.errors import ConfigError

__all__ = ["CONTROLLERS", "MaxPressure", "SignalMetrics", "SignalRun", "run_signal_baseline",
           "signal_program"]  # fmt: skip
#: Speed below which a car counts as queued, m/s.
QUEUE_SPEED = 0.1


@dataclass(frozen=True)
class SignalMetrics:
    """Outcome of one run.

    Attributes:
        mean_delay: time lost against driving the speed limit, per car that entered, s.
        mean_travel_time: mean time from departure to arrival of the cars that arrived, s.
        throughput: arrivals per hour, veh/h.
        mean_queue: mean number of queued cars (speed < 0.1 m/s) per step.
        waiting_at_end: cars in the network and queued at the end.
    """

    mean_delay: float
    mean_travel_time: float
    throughput: float
    mean_queue: float
    waiting_at_end: int

    def to_dict(self) -> dict[str, float]:
        """Plain dict for ``metrics.json``."""
        return asdict(self)


def _vertical(tk: Any, light: str) -> list[bool]:
    return [lane.split("_")[0].rstrip("0123456789") in ("left", "right")
            for lane in tk.get_controlled_lanes(light)]  # fmt: skip


def _edge(lane: str) -> str:
    return lane.rsplit("_", 1)[0]


class MaxPressure:
    """Max-pressure switching of every light (see the module docstring)."""

    def __init__(self, tk: Any, min_green: float, yellow: float, dt: float) -> None:
        self.tk = tk
        self.lights = tk.get_ids()
        self.vertical = [_vertical(tk, t) for t in self.lights]
        self.links = [[(_edge(a), _edge(b)) for a, b, _ in tk.get_controlled_links(t)]
                      for t in self.lights]  # fmt: skip
        self.timers = SwitchTimers(len(self.lights), yellow, dt)
        self.green_for = np.zeros(len(self.lights))
        self.min_green, self.dt = min_green, dt
        for i, t in enumerate(self.lights):
            tk.set_state(t, phase_state(self.vertical[i], 0, False))

    def step(self, edges: list[str]) -> None:
        """Decide the switches of this step from the cars' edges."""
        count = Counter(edges)
        switch = np.zeros(len(self.lights), dtype=bool)
        for i in range(len(self.lights)):
            if self.timers.currently_yellow[i] or self.green_for[i] < self.min_green:
                continue
            pressure = [0.0, 0.0]
            for (a, b), vert in zip(self.links[i], self.vertical[i], strict=True):
                pressure[0 if vert else 1] += count[a] - count[b]
            current = int(self.timers.direction[i])
            switch[i] = pressure[1 - current] > pressure[current]
        self.green_for += self.dt
        for i, direction, yellow in self.timers.step(switch):
            self.green_for[i] = 0.0
            self.tk.set_state(self.lights[i], phase_state(self.vertical[i], direction, yellow))


class SignalMeter:
    """Delay, travel times, arrivals and queues of one run, folded in step by step."""

    def __init__(self, env: Env) -> None:
        self.vk = env.k.vehicle
        self.dt = env.sim_step
        self.limit = max(e.speed for e in env.network.spec.edges)
        self.placed = env.initial_vehicles.num_vehicles
        self.steps = 0
        self.delay = self.queue = 0.0
        self.entered = 0
        self.travel: list[float] = []
        self.depart: dict[str, float] = {}

    def step(self, now: float) -> None:
        """Fold in the step that ended at simulation time ``now`` (s)."""
        vk = self.vk
        for vid in vk.get_departed_ids():
            self.depart[vid] = now
            self.entered += 1
        for vid in vk.get_arrived_ids():
            if vid in self.depart:
                self.travel.append(now - self.depart.pop(vid))
        speed = np.asarray(vk.speed, dtype=np.float64)
        self.delay += self.dt * float(np.sum((self.limit - speed) / self.limit))
        self.queue += int(np.count_nonzero(speed < QUEUE_SPEED))
        self.steps += 1

    def result(self) -> SignalMetrics:
        """The metrics of the steps so far."""
        hours = max(self.steps, 1) * self.dt / 3600.0
        return SignalMetrics(
            mean_delay=self.delay / max(self.entered + self.placed, 1),
            mean_travel_time=float(np.mean(self.travel)) if self.travel else float("nan"),
            throughput=len(self.travel) / hours,
            mean_queue=self.queue / max(self.steps, 1),
            waiting_at_end=int(np.count_nonzero(np.asarray(self.vk.speed) < QUEUE_SPEED)),
        )


class SignalRun:
    """A signal baseline as :class:`~flowrun.experiment.runner.Experiment` hooks: the
    controller's per-step decisions (max-pressure) and the :class:`SignalMetrics` of each run.

    Args:
        tls: the config's ``traffic_lights`` section (its ``controller`` decides; ``None``
            measures whatever programs the network runs).

    Attributes:
        results: the metrics of each finished run.
    """

    def __init__(self, tls: TrafficLightsConfig) -> None:
        self.tls = tls
        self.results: list[SignalMetrics] = []
        self._meter: SignalMeter | None = None
        self._mp: MaxPressure | None = None

    def on_reset(self, env: Env) -> None:
        """A run starts: loaded programs back in charge (an env may have set states), the
        max-pressure controller and the meter new."""
        tk = env.k.traffic_light
        lights = tk.get_ids()
        if self.tls.controller in ("fixed_time", "actuated"):
            for program in env.network.traffic_lights.programs(lights):
                if tk.get_program(program.node_id) != program.program_id:
                    tk.set_program(program.node_id, program.program_id)
        self._mp = None
        if self.tls.controller == "max_pressure":
            self._mp = MaxPressure(tk, self.tls.min_green, self.tls.yellow, env.sim_step)
        self._meter = SignalMeter(env)

    def before_step(self, env: Env) -> None:
        """Max-pressure decides this step's switches."""
        if self._mp is not None:
            self._mp.step(list(env.k.vehicle.edges))

    def after_step(self, env: Env) -> None:
        """Measure the step."""
        if self._meter is not None:
            self._meter.step(env.k.simulation.time)

    def on_run_end(self, env: Env, run: int) -> None:
        """Keep the run's metrics."""
        if self._meter is not None:
            self.results.append(self._meter.result())
        self._meter = None


def run_signal_baseline(
    cfg: ExperimentConfig, controller: str, seed: int, steps: int | None = None,
    min_green: float = 8.0, yellow: float = 3.0,
) -> SignalMetrics:  # fmt: skip
    """Run ``controller`` on the experiment's grid for ``steps`` steps (its horizon), with
    only human drivers (``TestEnv``).

    Raises:
        ConfigError: unknown controller, or a network without traffic lights.
    """
    if controller not in CONTROLLERS:
        raise ConfigError(f"unknown signal controller {controller!r}; expected one of "
                          f"{', '.join(CONTROLLERS)}", path="controller")  # fmt: skip
    tls = TrafficLightsConfig(controller=controller, min_green=min_green, yellow=yellow)
    network = make_network(replace(cfg, traffic_lights=tls))
    if not any(n.type == "traffic_light" for n in network.spec.nodes):
        raise ConfigError("the network has no traffic lights", path="network")
    env = TestEnv(EnvParams(horizon=10**9), replace(cfg.sim, seed=seed), network)
    n_steps = int(cfg.env.horizon if steps is None else steps)
    hooks = SignalRun(tls)
    try:
        env.reset(seed=seed)
        hooks.on_reset(env)
        for _ in range(n_steps):
            hooks.before_step(env)
            env.step(None)
            hooks.after_step(env)
        hooks.on_run_end(env, 0)
        return hooks.results[0]
    finally:
        env.close()
