"""Non-RL signal baselines on the traffic-light grid: fixed-time, SUMO's actuated, max-pressure.

* ``fixed_time``: every light runs a static program, Flow's phase lengths (31 s green,
  ``yellow`` s yellow per direction).
* ``actuated``: SUMO's gap-actuated program, Flow's ``TrafficLightParams(baseline=True)``
  (31 s [8, 45] green, 6 s yellow, max gap 3 s).
* ``max_pressure``: every step a light whose green has lasted ``min_green`` s switches (through
  ``yellow`` s of yellow) when the other direction's pressure is higher; the pressure of a
  direction is the sum over its links of (cars on the incoming edge - cars on the outgoing
  edge) (Varaiya, "Max pressure control of a network of signalized junctions", 2013).

:func:`run_signal_baseline` runs one on a grid experiment and returns the metrics. Not yet
wired into ``flowrun baseline`` (the YAML choice of the controller).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.config.params import EnvParams
from flowrun.config.traffic_lights import TrafficLightParams
from flowrun.envs.factory import make_network
from flowrun.envs.signals import SwitchTimers, phase_state
from flowrun.envs.test import TestEnv
from flowrun.errors import ConfigError

CONTROLLERS = ("fixed_time", "actuated", "max_pressure")
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


def signal_program(controller: str, lights: list[str], yellow: float) -> TrafficLightParams:
    """The lights' programs of a baseline (max-pressure: SUMO's default, then overridden)."""
    if controller == "actuated":
        return TrafficLightParams(baseline=True)
    tl = TrafficLightParams()
    if controller == "fixed_time":
        phases = [
            {"duration": 31, "state": "GrGr"},
            {"duration": yellow, "state": "yryr"},
            {"duration": 31, "state": "rGrG"},
            {"duration": yellow, "state": "ryry"},
        ]
        for light in lights:
            tl.add(light, phases=phases)
    return tl


def run_signal_baseline(
    cfg: ExperimentConfig, controller: str, seed: int, steps: int | None = None,
    min_green: float = 8.0, yellow: float = 3.0,
) -> SignalMetrics:  # fmt: skip
    """Run ``controller`` on the experiment's grid for ``steps`` steps (its horizon).

    Raises:
        ConfigError: unknown controller, or a network without traffic lights.
    """
    if controller not in CONTROLLERS:
        raise ConfigError(f"unknown signal controller {controller!r}; expected one of "
                          f"{', '.join(CONTROLLERS)}", path="controller")  # fmt: skip
    network = make_network(cfg)
    lights = [n.id for n in network.spec.nodes if n.type == "traffic_light"]
    if not lights:
        raise ConfigError("the network has no traffic lights", path="network")
    network.traffic_lights = signal_program(controller, lights, yellow)
    env = TestEnv(EnvParams(horizon=10**9), replace(cfg.sim, seed=seed), network)
    n_steps = int(cfg.env.horizon if steps is None else steps)
    try:
        env.reset(seed=seed)
        vk, dt = env.k.vehicle, env.sim_step
        mp = MaxPressure(env.k.traffic_light, min_green, yellow, dt) \
            if controller == "max_pressure" else None  # fmt: skip
        limit = max(e.speed for e in network.spec.edges)
        delay = queue = 0.0
        entered, travel, depart = 0, [], {}
        for _ in range(n_steps):
            if mp is not None:
                mp.step(list(vk.edges))
            env.step(None)
            now = env.k.simulation.time
            for vid in vk.get_departed_ids():
                depart[vid] = now
                entered += 1
            for vid in vk.get_arrived_ids():
                if vid in depart:
                    travel.append(now - depart.pop(vid))
            speed = np.asarray(vk.speed, dtype=np.float64)
            delay += dt * float(np.sum((limit - speed) / limit))
            queue += int(np.count_nonzero(speed < QUEUE_SPEED))
        hours = n_steps * dt / 3600.0
        return SignalMetrics(
            mean_delay=delay / max(entered + env.initial_vehicles.num_vehicles, 1),
            mean_travel_time=float(np.mean(travel)) if travel else float("nan"),
            throughput=len(travel) / hours,
            mean_queue=queue / n_steps,
            waiting_at_end=int(np.count_nonzero(np.asarray(vk.speed) < QUEUE_SPEED)),
        )
    finally:
        env.close()
