"""``BottleneckEnv``: the bottleneck without an agent, and Flow's toll booth and ramp meter.

Vinitsky, Parvate, Kreidieh, Wu, Hu, Bayen, "Lagrangian Control through Deep-RL:
Applications to Bottleneck Decongestion", IEEE ITSC 2018. On Flow's
:class:`~flowrun.networks.bottleneck.BottleneckNetwork` four lanes narrow to two and then to
one; once the inflow passes what the merges can take (about 2,100 veh/h at scaling 1 with
SUMO 1.28's drivers; Flow reports about 1,600) they break down and the outflow *drops* to
about 1,460 veh/h (``bench/bottleneck.py``). The RL envs (:mod:`flowrun.envs.bottleneck`,
Flow's module) build on this one.

Flow's toll booth and ALINEA ramp meter (``disable_tb`` / ``disable_ramp_metering`` false)
are traffic lights on nodes ``2`` and ``3``. Both hold the cars that approach them in their
lane (SUMO lane-change mode 512, no lane changes) and give them back their own mode once
they are past.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.base import Env
from flowrun.errors import ConfigError

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



#: Flow's largest number of lanes per unit of ``scaling``
MAX_LANES = 4

#: Flow's toll booth: mean waits (s) at a normal and a fast-track booth, the distance into
#: edge ``1`` (m) after which cars stop changing lanes, and after which the booth holds them
MEAN_WAIT_TOLL, MEAN_WAIT_FAST_TRACK = 15.0, 3.0
TOLL_BOOTH_AREA, TOLL_STOP_AREA = 10.0, 50.0
#: Flow's ramp meter: the distance into edge ``2`` (m) after which cars stop changing lanes
RAMP_METER_AREA = 80.0
#: SUMO lane-change mode of a car held in its lane (Flow's ``no_lc_safe``)
HOLD_LANE = 512


class _LaneHold:
    """Cars held in their lane: id -> their own lane-change mode, given back later."""

    def __init__(self) -> None:
        self.held: dict[str, int] = {}

    def hold(self, vk: Any, veh_id: str) -> None:
        self.held[veh_id] = vk.get_lane_change_mode(veh_id)
        vk.set_lane_change_mode(veh_id, HOLD_LANE)

    def release_on(self, vk: Any, edge: str) -> list[str]:
        """Give their mode back to the held cars now on ``edge`` (forget those gone)."""
        out = []
        for veh_id in list(self.held):
            if veh_id not in vk.table:
                del self.held[veh_id]
            elif vk.get_edge(veh_id) == edge:
                vk.set_lane_change_mode(veh_id, self.held.pop(veh_id))
                out.append(veh_id)
        return out


def _on_edge(vk: Any, edge: str, beyond: float) -> list[tuple[str, int, float]]:
    """``(id, lane, position)`` of the cars on ``edge`` more than ``beyond`` m into it."""
    ids, edges, lanes, pos = vk.table.ids, vk.edges, vk.lanes, vk.lane_pos
    return [(ids[i], int(lanes[i]), float(pos[i]))
            for i, e in enumerate(edges) if e == edge and pos[i] > beyond]  # fmt: skip


class TollBooth:
    """Flow's toll booth on node ``2``: each lane's light stays red for a random wait.

    A lane's wait (in steps) is drawn from a normal law, mean 15 s (3 s at the fast-track
    booths, the middle lanes), sd 1 s, and counts down while a car stands in the last
    50 m of edge ``1``; the next wait is drawn when a car passes.
    """

    def __init__(self, scaling: int, dt: float, rng: np.random.Generator) -> None:
        self.dt, self.rng = dt, rng
        n = MAX_LANES * scaling
        self.fast_track = range(math.ceil(1.5 * scaling), math.ceil(2.6 * scaling))
        self.wait = np.abs(rng.normal(MEAN_WAIT_TOLL / dt, 4 / dt, n))
        self.state = ""
        self.lanes = _LaneHold()

    def step(self, k: Any) -> None:
        """Release the cars past the booth, hold the ones in it, set the lights."""
        vk = k.vehicle
        for veh_id in self.lanes.release_on(vk, "2"):
            lane = vk.get_lane(veh_id)
            mean = MEAN_WAIT_FAST_TRACK if lane in self.fast_track else MEAN_WAIT_TOLL
            self.wait[lane] = max(0.0, float(self.rng.normal(mean / self.dt, 1 / self.dt)))
        lights = ["G"] * self.wait.size
        for veh_id, lane, pos in _on_edge(vk, "1", TOLL_BOOTH_AREA):
            if veh_id not in self.lanes.held:
                self.lanes.hold(vk, veh_id)
            elif pos > TOLL_STOP_AREA and lane < self.wait.size and self.wait[lane] >= 0:
                lights[lane] = "r"  # Flow counts the wait down per waiting car
                self.wait[lane] -= 1
        state = "".join(lights)
        if state != self.state:
            self.state = state
            k.traffic_light.set_state("2", state)


#: Flow's optional ``additional_params`` of the ramp meter, with its defaults: the critical
#: number of cars on edge ``4``, the metered flow's bounds (veh/h), the update period (s) and
#: the feedback gain
RAMP_METER_PARAMS: dict[str, float] = {
    "n_crit": 8,
    "q_max": 1100,
    "q_min": 0.25 * 1100,
    "feedback_update": 15,
    "feedback_coeff": 20,
}


class RampMeter:
    """Flow's ALINEA ramp meter on node ``3`` (Spiliopoulou, Papamichail, Papageorgiou,
    "Toll plaza merging traffic control for throughput maximization", J. Transp. Eng. 2009).

    Every ``feedback_update`` s the metered flow ``q`` (veh/h) moves by
    ``feedback_coeff * (n_crit - n)``, ``n`` the mean number of cars on edge ``4`` over the
    last 10 steps, within ``[q_min, q_max]``; each lane's light is green for the first
    ``green_time`` = 4 s of every ``7200 / q`` s cycle, the lanes' cycles offset by 8 s.
    """

    def __init__(self, scaling: int, dt: float, params: dict[str, Any]) -> None:
        self.dt = dt
        p = {**RAMP_METER_PARAMS, **params}
        self.n_crit = float(p["n_crit"])
        self.q_max = float(p["q_max"])
        self.q_min = float(p["q_min"])
        self.feedback_update = float(p["feedback_update"])
        self.feedback_coeff = float(p["feedback_coeff"])
        self.q = self.q_min
        self.cycle_time, self.green_time, self.timer = 6.0, 4.0, 0.0
        n = MAX_LANES * scaling
        self.ramp_state = np.linspace(0, 8 * n, n)
        self.lanes = _LaneHold()

    def step(self, k: Any, cars_in_bottleneck: list[int]) -> None:
        """Hold the cars approaching the meter, update ALINEA, set the lights."""
        vk = k.vehicle
        self.lanes.release_on(vk, "3")
        for veh_id, _, _ in _on_edge(vk, "2", RAMP_METER_AREA):
            if veh_id not in self.lanes.held:
                self.lanes.hold(vk, veh_id)
        self.timer += self.dt
        self.ramp_state += self.dt
        if self.timer > self.feedback_update:
            self.timer = 0.0
            update = self.feedback_coeff * (self.n_crit - float(np.mean(cars_in_bottleneck)))
            self.q = float(np.clip(self.q + update, self.q_min, self.q_max))
            self.cycle_time = 7200.0 / self.q
        self.ramp_state %= self.cycle_time
        state = "".join("G" if s <= self.green_time else "r" for s in self.ramp_state)
        k.traffic_light.set_state("3", state)


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
    (:class:`TollBooth`, :class:`RampMeter`; each needs a traffic light on its node).
    """

    DEFAULT_EXPERIMENT = "benchmarks/bottleneck0.yaml"

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS
    OPTIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = RAMP_METER_PARAMS

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
