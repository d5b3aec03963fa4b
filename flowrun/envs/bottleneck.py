"""``BottleneckEnv``: the bottleneck's base environment (Flow's ``flow.envs.bottleneck``).

Vinitsky, Parvate, Kreidieh, Wu, Hu, Bayen, "Lagrangian Control through Deep-RL:
Applications to Bottleneck Decongestion", IEEE ITSC 2018. On Flow's
:class:`~flowrun.networks.bottleneck.BottleneckNetwork` four lanes narrow to two and then to
one; once the inflow passes what the merges can take (about 2,100 veh/h at scaling 1 with
SUMO 1.28's drivers; Flow reports about 1,600) they break down and the outflow *drops* to
about 1,460 veh/h (``bench/bottleneck.py``). The RL envs (:mod:`flowrun.envs.bottleneck_accel`,
:mod:`flowrun.envs.bottleneck_velocity`) build on this one.
"""

from __future__ import annotations

from collections import deque
from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.base import Env
from flowrun.envs.bottleneck_control import MAX_LANES, RampMeter, TollBooth
from flowrun.errors import ConfigError

__all__ = ["ADDITIONAL_ENV_PARAMS", "MAX_LANES", "BottleneckEnv"]

#: Flow's ``flow.envs.bottleneck`` also holds the RL envs: served from their modules
_RL_NAMES = {
    "BottleneckAccelEnv": "flowrun.envs.bottleneck_accel",
    "ADDITIONAL_RL_ENV_PARAMS": "flowrun.envs.bottleneck_accel",
    "BottleneckDesiredVelocityEnv": "flowrun.envs.bottleneck_velocity",
    "DesiredVelocityEnv": "flowrun.envs.bottleneck_velocity",
    "ADDITIONAL_VSL_ENV_PARAMS": "flowrun.envs.bottleneck_velocity",
}


def __getattr__(name: str) -> Any:
    """Flow's import path ``flow.envs.bottleneck`` for the RL bottleneck envs."""
    if name in _RL_NAMES:
        import importlib

        return getattr(importlib.import_module(_RL_NAMES[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: Flow's constants: the edges in driving order, the length of the bottleneck (edge ``4``,
#: m), and the vehicle count that normalises observations.
EDGE_LIST = ("1", "2", "3", "4", "5")
BOTTLENECK_LEN = 280.0
NUM_VEHICLE_NORM = 20.0

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AVs, m/s^2
    "max_accel": 3,
    # maximum deceleration of the AVs, m/s^2
    "max_decel": 3,
    # steps an AV waits after a lane change before it may change again (Flow's counter
    # counts simulation steps although its comment says seconds)
    "lane_change_duration": 5,
    # no toll booth (false: Flow's toll booth, a traffic light on node 2)
    "disable_tb": True,
    # no ramp meter (false: Flow's ALINEA ramp meter, a traffic light on node 3)
    "disable_ramp_metering": True,
}

#: the node each of Flow's controls needs a traffic light on
CONTROL_NODES = {"disable_tb": ("2", "toll booth"), "disable_ramp_metering": ("3", "ramp meter")}


def enabled_controls(params: dict[str, Any], lights: set[str]) -> set[str]:
    """Which of Flow's controls (``disable_tb``, ``disable_ramp_metering``) are on.

    Raises:
        ConfigError: a control is on but its node has no traffic light.
    """
    on = set()
    for key, (node, what) in CONTROL_NODES.items():
        if not params.get(key, True):
            if node not in lights:
                raise ConfigError(
                    f"the {what} ({key}: false) switches a traffic light on node {node!r}; "
                    f"add one (traffic_lights: {{lights: [{{node_id: '{node}'}}]}})",
                    path=f"env.additional_params.{key}",
                )
            on.add(key)
    return on


class BottleneckEnv(Env):
    """The bottleneck without an agent (Flow's ``BottleneckEnv``): what ``flowrun baseline``
    runs on the bottleneck, and the base of the RL bottleneck envs.

    Observation: Flow's dummy ``[1]`` (``Box(-inf, inf, (1,))``). Action: none used
    (``Box(-inf, inf, (1,))``). Reward: the outflow over the last ``10 * sim_step`` s
    divided by ``2000 * scaling`` veh/h. Termination: collision; truncation: horizon.
    ``info`` adds ``outflow`` (veh/h over the last ``10 * sim_step`` s) and
    ``lane_changes`` (all cars', since the episode's first observation) to the base's keys.
    Flow's ``smoothed_num`` (cars on edge ``4`` over the last 10 steps) is kept current.
    With ``disable_tb: false`` Flow's toll booth runs on node ``2``, with
    ``disable_ramp_metering: false`` its ALINEA ramp meter on node ``3``
    (:mod:`flowrun.envs.bottleneck_control`; each needs a traffic light on its node).
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        lights = set(self.network.traffic_lights.get_properties())
        self._controls = enabled_controls(self.env_params.additional_params, lights)
        #: Flow's factor multiplying the number of lanes
        self.scaling = int(self.net_params.additional_params.get("scaling", 1))
        #: cars on the bottleneck edge ``4`` at each of the last 10 simulation steps
        self.smoothed_num: deque[int] = deque([0] * 10, maxlen=10)
        self.toll_booth: TollBooth | None = None
        self.ramp_meter: RampMeter | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start a new episode (the edge-``4`` counts start at zero; the toll booth's waits
        are drawn from the env's seeded generator)."""
        self.smoothed_num = deque([0] * 10, maxlen=10)
        self.toll_booth = self.ramp_meter = None  # new ones at the episode's first step
        return super().reset(seed=seed, options=options)

    @property
    def action_space(self) -> Box:  # type: ignore[override]
        """Flow's dummy action space."""
        return Box(low=-np.inf, high=np.inf, shape=(1,), dtype=np.float32)

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """Flow's dummy observation space."""
        return Box(low=-np.inf, high=np.inf, shape=(1,), dtype=np.float32)

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        """No agent acts here."""

    def get_state(self) -> Any:
        """Flow's dummy observation ``[1]``."""
        return np.ones(1)

    def additional_command(self) -> None:
        """Flow's: run the toll booth and the ramp meter if on, count the cars on edge ``4``."""
        on = self._controls
        if "disable_tb" in on:
            if self.toll_booth is None:
                rng = np.random.default_rng(int(self.np_random.integers(2**63 - 1)))
                self.toll_booth = TollBooth(self.scaling, self.sim_step, rng)
            self.toll_booth.step(self.k)
        if "disable_ramp_metering" in on:
            if self.ramp_meter is None:
                p = self.env_params.additional_params
                self.ramp_meter = RampMeter(self.scaling, self.sim_step, p)
            self.ramp_meter.step(self.k, list(self.smoothed_num))
        self.smoothed_num.append(len(self.k.vehicle.get_ids_by_edge("4")))

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Outflow over the last ``10 * sim_step`` s, normalised by ``2000 * scaling``."""
        return self.k.vehicle.get_outflow_rate(10 * self.sim_step) / (2000.0 * self.scaling)

    def get_bottleneck_density(self, lanes: list[str] | None = None) -> float:
        """Cars per metre on edges ``3`` and ``4`` (only on ``lanes``, ids ``"edge_lane"``,
        if given), over Flow's bottleneck length of 280 m."""
        vk = self.k.vehicle
        ids = vk.get_ids_by_edge(["3", "4"])
        if lanes:
            ids = [v for v in ids if f"{vk.get_edge(v)}_{vk.get_lane(v)}" in lanes]
        return len(ids) / BOTTLENECK_LEN

    def _info(self, crash: bool) -> dict[str, Any]:
        info = super()._info(crash)
        vk = self.k.vehicle
        info["outflow"] = vk.get_outflow_rate(10 * self.sim_step)
        info["lane_changes"] = vk.num_lane_changes  # since the first observation (logged on)
        return info
