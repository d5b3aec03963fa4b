"""Vehicle groups (Flow's ``VehicleParams``): who drives, how many, with which SUMO vType.

A group is one ``VehicleParams.add`` call. Besides flowrun's typed ``groups``, the Flow
attributes that Flow code reads are there, computed from the groups: ``type_parameters``
(by type: the controllers as ``(class, params)``, ``initial_speed``, the two SUMO parameter
objects — the very objects of the group, so changing them changes the group), ``types``
(``[{"veh_id": ..., "type_params": {SUMO attributes}}]``), ``minGap`` (by type),
``initial``, ``ids``, ``num_vehicles``, ``num_rl_vehicles``, ``num_types``.
"""

from __future__ import annotations

import builtins
from dataclasses import dataclass, field
from typing import Any, ClassVar

from flowrun.config.vtype import SumoCarFollowingParams, SumoLaneChangeParams, vtype_attributes
from flowrun.controllers.registry import resolve_controller


@dataclass(frozen=True)
class ControllerSpec:
    """A controller by registered name (``IDM``) or import path, with its parameters.

    ``cls`` is the class object when one was given (Flow's ``(IDMController, {})``); it is
    not part of the YAML and not compared.
    """

    type: str
    params: dict[str, Any] = field(default_factory=dict)
    cls: builtins.type | None = field(
        default=None, compare=False, repr=False, metadata={"yaml": False}
    )


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


ControllerArg = tuple[Any, dict[str, Any] | None] | ControllerSpec | None


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
    return ControllerSpec(name, dict(params or {}), cls)


def controller_tuple(spec: ControllerSpec | None) -> tuple[Any, dict[str, Any]] | None:
    """Flow's ``(ControllerClass, params)`` of a spec (the name when it cannot be resolved)."""
    if spec is None:
        return None
    cls: Any = spec.cls
    if cls is None:
        try:
            cls = resolve_controller(spec.type)
        except Exception:  # an unknown name: validation reports it where it matters
            cls = spec.type
    return cls, dict(spec.params)


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
    def type_names(self) -> list[str]:
        """Group names (``veh_id``) in the order they were added."""
        return [g.veh_id for g in self.groups]

    @property
    def types(self) -> list[dict[str, Any]]:
        """Flow's list of ``{"veh_id": name, "type_params": {SUMO vType attributes}}``.

        ``type_params`` is Flow's: the car-following and lane-change ``controller_params``
        (plus ``color`` when the group has one). A fresh list at each read.
        """
        out = []
        for g in self.groups:
            params: dict[str, Any] = dict(g.car_following_params.controller_params)
            params.update(g.lane_change_params.controller_params)
            if g.color:
                params["color"] = g.color
            out.append({"veh_id": g.veh_id, "type_params": params})
        return out

    @property
    def type_parameters(self) -> dict[str, dict[str, Any]]:
        """Flow's dict by type: ``acceleration_controller``, ``lane_change_controller``,
        ``routing_controller`` (``(class, params)`` or ``None``), ``initial_speed``,
        ``car_following_params``, ``lane_change_params`` (the group's own objects), and
        ``color`` when set. A fresh dict at each read."""
        out: dict[str, dict[str, Any]] = {}
        for g in self.groups:
            entry: dict[str, Any] = {
                "acceleration_controller": controller_tuple(g.acceleration_controller),
                "lane_change_controller": controller_tuple(g.lane_change_controller),
                "routing_controller": controller_tuple(g.routing_controller),
                "initial_speed": g.initial_speed,
                "car_following_params": g.car_following_params,
                "lane_change_params": g.lane_change_params,
            }
            if g.color:
                entry["color"] = g.color
            out[g.veh_id] = entry
        return out

    @property
    def minGap(self) -> dict[str, float]:
        """Flow's SUMO ``minGap`` of each type, m."""
        return {g.veh_id: g.car_following_params.min_gap for g in self.groups}

    @property
    def initial(self) -> list[dict[str, Any]]:
        """Flow's record of each ``add`` call (its arguments, controllers as tuples)."""
        return [
            {
                "veh_id": g.veh_id,
                "acceleration_controller": controller_tuple(g.acceleration_controller),
                "lane_change_controller": controller_tuple(g.lane_change_controller),
                "routing_controller": controller_tuple(g.routing_controller),
                "initial_speed": g.initial_speed,
                "num_vehicles": g.num_vehicles,
                "car_following_params": g.car_following_params,
                "lane_change_params": g.lane_change_params,
            }
            for g in self.groups
        ]

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

    def vtype_attributes(self, veh_id: str) -> dict[str, str]:
        """The SUMO ``<vType>`` attributes of group ``veh_id`` (see :func:`vtype_attributes`)."""
        g = self.get_type(veh_id)
        return vtype_attributes(g.car_following_params, g.lane_change_params)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, VehicleParams) and self.groups == other.groups

    def __repr__(self) -> str:
        return f"VehicleParams({self.groups!r})"


def is_rl(group: VehicleType) -> bool:
    """Whether a group is driven by the RL agent."""
    return group.acceleration_controller.type in ("RLController", "RL")
