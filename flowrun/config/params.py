"""Flow's parameter objects, as typed data. The YAML config is made of exactly these.

Each class mirrors the Flow class of the same name (same field names and defaults, except where
a default is documented as deliberately different). ``YAML_KEYS`` maps a YAML key to a field
name where the config uses a shorter spelling (``sim.step`` -> ``SumoParams.sim_step``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

from flowrun.config.inflows import InFlow as InFlow
from flowrun.config.inflows import InFlows as InFlows

# Flow's speed modes (SUMO speedMode bit sets) and lane-change modes (laneChangeMode bit sets).
SPEED_MODES: dict[str, int] = {
    "aggressive": 0,
    "obey_safe_speed": 1,
    "no_collide": 7,
    "right_of_way": 25,
    "all_checks": 31,
}
LANE_CHANGE_MODES: dict[str, int] = {
    "no_lc_safe": 512,
    "no_lc_aggressive": 0,
    "sumo_default": 1621,
    "no_cooperative_safe": 1621 - 12,
    "only_strategic_safe": 1621 - 12 - 48,
    "only_strategic_aggressive": 1,
    "no_strategic_safe": 1621 - 3,
    "no_strategic_aggressive": 1621 - 3 - 512,
    "aggressive": 0b0101010101,
    "only_speed_gain_safe": 1621 - 3 - 12,
    "only_speed_gain_aggressive": 0b0000010000,
    "only_cooperative_safe": 1621 - 3 - 48,
    "only_cooperative_aggressive": 0b0000000100,
}


@dataclass(frozen=True)
class SumoParams:
    """Simulation settings (Flow's ``SumoParams``).

    Attributes:
        sim_step: seconds per simulation step (YAML key ``step``).
        seed: seed of every random draw (SUMO's and flowrun's); ``None`` means 0.
        render: open ``sumo-gui`` through TraCI. Without a display flowrun warns and runs
            headless instead, so scripts written for a desktop still run on a server.
        teleport_time: SUMO ``--time-to-teleport``; -1 disables teleporting of stuck cars.
        use_ballistic: ballistic position update instead of SUMO's default Euler update.
        lateral_resolution: SUMO's sublane model resolution in metres; ``None`` disables it.
        emission_path: accepted for Flow compatibility; flowrun logs to MCAP instead.
        print_warnings: show SUMO's own warnings.
        restart_instance: accepted for Flow compatibility (flowrun always restarts cheaply).
    """

    YAML_KEYS: ClassVar[dict[str, str]] = {"step": "sim_step"}

    sim_step: float = 0.1
    seed: int | None = None
    render: bool = False
    teleport_time: float = -1.0
    use_ballistic: bool = False
    lateral_resolution: float | None = None
    emission_path: str | None = None
    print_warnings: bool = False
    restart_instance: bool = False


@dataclass(frozen=True)
class EnvParams:
    """Environment settings (Flow's ``EnvParams``).

    Attributes:
        env_class: name of a built-in environment or ``package.module:Class`` (YAML key
            ``class``). ``None`` means ``AccelEnv``.
        horizon: RL steps per episode; the episode is *truncated* after it.
        warmup_steps: steps run with no RL action at each reset before the episode starts.
        sims_per_step: simulation steps per RL step (actions held constant).
        clip_actions: clip RL actions to the action space.
        evaluate: Flow's flag for evaluation-mode rewards.
        additional_params: the environment's own parameters (its ``ADDITIONAL_ENV_PARAMS``).
    """

    YAML_KEYS: ClassVar[dict[str, str]] = {"class": "env_class"}

    additional_params: dict[str, Any] = field(default_factory=dict)
    horizon: float = math.inf
    warmup_steps: int = 0
    sims_per_step: int = 1
    evaluate: bool = False
    clip_actions: bool = True
    env_class: str | None = None


@dataclass(frozen=True)
class NetParams:
    """Network parameters (Flow's ``NetParams``): the network type's ``additional_params``."""

    additional_params: dict[str, Any] = field(default_factory=dict)
    inflows: InFlows | None = None
    template: str | None = None
    osm_path: str | None = None


@dataclass(frozen=True)
class InitialConfig:
    """Initial placement of the vehicles (Flow's ``InitialConfig``).

    Attributes:
        shuffle: shuffle the order of vehicle types along the road (seeded).
        spacing: ``uniform`` (evenly spaced) or ``random`` (uniformly random gaps).
        min_gap: extra bumper-to-bumper gap kept between cars when placing them, metres.
        perturbation: std of a Gaussian offset added to each uniform position, metres.
        x0: position of the first car along the network, metres.
        bunching: metres of road left empty; cars fill ``length - bunching``.
        lanes_distribution: how many lanes cars are spread over (``inf`` = all lanes).
        edges_distribution: ``all`` or a list of edge names to place cars on.
    """

    shuffle: bool = False
    spacing: str = "uniform"
    min_gap: float = 0.0
    perturbation: float = 0.0
    x0: float = 0.0
    bunching: float = 0.0
    lanes_distribution: float = math.inf
    edges_distribution: str | list[str] = "all"
    additional_params: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class SumoCarFollowingParams:
    """SUMO vehicle-type parameters (Flow's ``SumoCarFollowingParams``).

    flowrun's defaults differ from Flow's in two places, on purpose:
    ``speed_mode="aggressive"`` (SUMO applies a controller's command as is; Flow's
    ``right_of_way`` lets SUMO's safe-speed cap damp IDM braking) and ``speed_dev=0``
    (homogeneous drivers, as in the published ring results).

    Attributes:
        speed_mode: one of :data:`SPEED_MODES` or an int SUMO speedMode.
        accel: max acceleration SUMO's own model may use, m/s^2.
        decel: comfortable deceleration SUMO's own model may use, m/s^2.
        sigma: driver imperfection of SUMO's own model (0..1).
        tau: desired time headway of SUMO's own model, s.
        min_gap: standstill gap SUMO keeps, m.
        max_speed: vehicle-type maximum speed, m/s.
        speed_factor: multiplier of the lane speed limit.
        speed_dev: std of the speed factor across vehicles.
        impatience: SUMO impatience (0..1).
        car_follow_model: SUMO's car-following model for SUMO-driven cars.
        length: vehicle length, m.
    """

    speed_mode: str | int = "aggressive"
    accel: float = 2.6
    decel: float = 7.5
    sigma: float = 0.5
    tau: float = 1.0
    min_gap: float = 2.5
    max_speed: float = 30.0
    speed_factor: float = 1.0
    speed_dev: float = 0.0
    impatience: float = 0.5
    car_follow_model: str = "IDM"
    length: float = 5.0


@dataclass(frozen=True)
class SumoLaneChangeParams:
    """SUMO lane-change parameters (Flow's ``SumoLaneChangeParams``).

    Attributes:
        lane_change_mode: one of :data:`LANE_CHANGE_MODES` or an int SUMO laneChangeMode.
        model: SUMO lane-change model (``LC2013`` or ``SL2015``).
        lc_strategic: eagerness for strategic lane changes.
        lc_cooperative: willingness to cooperate.
        lc_speed_gain: eagerness to change lanes for speed.
        lc_keep_right: eagerness to keep right.
    """

    lane_change_mode: str | int = "no_lc_safe"
    model: str = "LC2013"
    lc_strategic: float = 1.0
    lc_cooperative: float = 1.0
    lc_speed_gain: float = 1.0
    lc_keep_right: float = 1.0


@dataclass(frozen=True)
class ControllerSpec:
    """A controller by registered name (``IDM``) or import path, with its parameters."""

    type: str
    params: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class VehicleType:
    """One group of identical vehicles (one ``VehicleParams.add`` call).

    Vehicles are named ``{veh_id}_{i}`` for ``i`` in ``range(num_vehicles)``, as in Flow.
    YAML keys: ``id``, ``count``, ``car_following``, ``lane_change``.
    """

    YAML_KEYS: ClassVar[dict[str, str]] = {
        "id": "veh_id",
        "count": "num_vehicles",
        "car_following": "car_following_params",
        "lane_change": "lane_change_params",
    }

    veh_id: str
    num_vehicles: int = 0
    acceleration_controller: ControllerSpec = field(
        default_factory=lambda: ControllerSpec("SimCarFollowingController")
    )
    lane_change_controller: ControllerSpec = field(
        default_factory=lambda: ControllerSpec("SimLaneChangeController")
    )
    routing_controller: ControllerSpec | None = None
    initial_speed: float = 0.0
    car_following_params: SumoCarFollowingParams = field(default_factory=SumoCarFollowingParams)
    lane_change_params: SumoLaneChangeParams = field(default_factory=SumoLaneChangeParams)
    color: str | None = None


ControllerArg = tuple[Any, dict[str, Any]] | ControllerSpec | None


def controller_spec(arg: ControllerArg) -> ControllerSpec | None:
    """Turn Flow's ``(ControllerClass, {params})`` tuple into a :class:`ControllerSpec`."""
    if arg is None or isinstance(arg, ControllerSpec):
        return arg
    cls, params = arg
    if isinstance(cls, str):
        return ControllerSpec(cls, dict(params or {}))
    name = getattr(cls, "registered_name", None)
    if name is None or getattr(cls, "__module__", "").split(".")[0] != "flowrun":
        name = f"{cls.__module__}:{cls.__qualname__}"
    return ControllerSpec(name, dict(params or {}))


class VehicleParams:
    """The vehicles of an experiment (Flow's ``VehicleParams``): a list of vehicle groups."""

    def __init__(self, groups: list[VehicleType] | None = None) -> None:
        self.groups: list[VehicleType] = list(groups or [])

    def add(
        self,
        veh_id: str,
        acceleration_controller: ControllerArg = None,
        lane_change_controller: ControllerArg = None,
        routing_controller: ControllerArg = None,
        initial_speed: float = 0.0,
        num_vehicles: int = 0,
        car_following_params: SumoCarFollowingParams | None = None,
        lane_change_params: SumoLaneChangeParams | None = None,
        color: str | None = None,
    ) -> None:
        """Add a group of ``num_vehicles`` vehicles named ``{veh_id}_{i}`` (Flow's signature)."""
        self.groups.append(
            VehicleType(
                veh_id=veh_id,
                num_vehicles=num_vehicles,
                acceleration_controller=controller_spec(acceleration_controller)
                or ControllerSpec("SimCarFollowingController"),
                lane_change_controller=controller_spec(lane_change_controller)
                or ControllerSpec("SimLaneChangeController"),
                routing_controller=controller_spec(routing_controller),
                initial_speed=initial_speed,
                car_following_params=car_following_params or SumoCarFollowingParams(),
                lane_change_params=lane_change_params or SumoLaneChangeParams(),
                color=color,
            )
        )

    @property
    def num_vehicles(self) -> int:
        """Total number of vehicles over all groups."""
        return sum(g.num_vehicles for g in self.groups)

    @property
    def num_rl_vehicles(self) -> int:
        """Number of vehicles driven by the RL agent (``RLController``)."""
        return sum(g.num_vehicles for g in self.groups if is_rl(g))

    @property
    def num_types(self) -> int:
        """Number of vehicle groups."""
        return len(self.groups)

    @property
    def types(self) -> list[str]:
        """Group names in the order they were added."""
        return [g.veh_id for g in self.groups]

    @property
    def ids(self) -> list[str]:
        """All vehicle ids in placement order."""
        return [f"{g.veh_id}_{i}" for g in self.groups for i in range(g.num_vehicles)]

    def get_type(self, veh_id: str) -> VehicleType:
        """The group named ``veh_id``."""
        for g in self.groups:
            if g.veh_id == veh_id:
                return g
        raise KeyError(veh_id)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, VehicleParams) and self.groups == other.groups

    def __repr__(self) -> str:
        return f"VehicleParams({self.groups!r})"


def is_rl(group: VehicleType) -> bool:
    """Whether a group is driven by the RL agent."""
    return group.acceleration_controller.type in ("RLController", "RL")


class TrafficLightParams:
    """Traffic lights (Flow's ``TrafficLightParams``); kept as data for networks that use them."""

    def __init__(self, baseline: bool = False) -> None:
        self.baseline = baseline
        self.lights: dict[str, dict[str, Any]] = {}

    def add(self, node_id: str, **kwargs: Any) -> None:
        """Describe the traffic light at ``node_id`` (phases, programID, tls_type, ...)."""
        self.lights[node_id] = dict(kwargs)

    def get_properties(self) -> dict[str, dict[str, Any]]:
        """All traffic lights by node id."""
        return dict(self.lights)
