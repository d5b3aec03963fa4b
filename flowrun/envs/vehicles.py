"""From ``VehicleParams`` to the kernel's vehicle table and the per-group controller objects."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flowrun.config.params import VehicleParams
from flowrun.controllers.base import AccelerationController
from flowrun.controllers.drivers import FlowStyleDriver
from flowrun.controllers.per_vehicle import PerVehicleGroup
from flowrun.controllers.registry import build_controller, resolve_controller
from flowrun.controllers.view import VehicleControllerView
from flowrun.kernel.population import Population, VehicleClass, VehicleTable
from flowrun.networks.base import NetworkSpec, StartPositions
from flowrun.networks.routes import route_name


@dataclass
class GroupControl:
    """The acceleration controller of one vehicle group and the vehicle rows it drives."""

    name: str
    index: np.ndarray
    controller: AccelerationController
    #: the same rows as a slice when they are contiguous (a view, no copy), else ``index``
    sl: slice | np.ndarray = field(init=False)
    #: the population version ``index`` was taken from
    version: int = -1

    def __post_init__(self) -> None:
        self._set_slice()

    def _set_slice(self) -> None:
        idx = self.index
        start = int(idx[0]) if idx.size else 0
        contiguous = idx.size == 0 or int(idx[-1]) - start + 1 == idx.size
        self.sl = slice(start, start + int(idx.size)) if contiguous else idx

    def follow(self, population: Population, group: int) -> None:
        """Take the group's rows from the population when vehicles came or went.

        A controller with per-vehicle memory starts afresh when its group's size changes.
        """
        if population.version == self.version:
            return
        self.version = population.version
        old = self.index.size
        self.index = population.rows_of_group(group)
        self._set_slice()
        if self.index.size != old:
            self.controller.reset(self.index.size)


def build_controllers(vehicles: VehicleParams) -> list[GroupControl]:
    """One acceleration controller per group, with the indices of its vehicles."""
    controls = []
    start = 0
    for g in vehicles.groups:
        idx = np.arange(start, start + g.num_vehicles)
        start += g.num_vehicles
        spec = g.acceleration_controller
        ctrl: Any = build_controller(spec.cls or spec.type, dict(spec.params))
        controls.append(GroupControl(g.veh_id, idx, ctrl))
    return controls


def _routed_continuously(route_type: str | None) -> bool:
    if route_type is None:
        return False
    cls = resolve_controller(route_type)
    return bool(getattr(cls, "registered_name", cls.__name__) == "ContinuousRouter")


def build_table(
    vehicles: VehicleParams,
    controls: list[GroupControl],
    start: StartPositions,
    spec: NetworkSpec,
    rng: np.random.Generator,
) -> VehicleTable:
    """The vehicles at the start of an episode and every group's static facts.

    A vehicle starting on an edge with several route choices gets one drawn from ``rng``.
    """
    classes = []
    ids: list[str] = []
    group: list[int] = []
    initial: list[float] = []
    for gi, (g, ctl) in enumerate(zip(vehicles.groups, controls, strict=True)):
        c = ctl.controller
        cf = g.car_following_params
        routed = _routed_continuously(g.routing_controller.type if g.routing_controller else None)
        classes.append(
            VehicleClass(
                name=g.veh_id,
                is_rl=bool(c.is_rl),
                commanded=bool(c.commands_sumo and not c.is_rl),
                continuous=routed,
                lane_controlled=bool(
                    resolve_controller(g.lane_change_controller.type).commands_sumo
                ),
                length=float(cf.length),
                min_gap=float(cf.min_gap),
                max_speed=float(cf.max_speed),
                accel=float(cf.accel),
                decel=float(cf.decel),
                # stored as SUMO's ints by the parameter classes (a name is turned into one)
                speed_mode=int(cf.speed_mode),
                lane_change_mode=int(g.lane_change_params.lane_change_mode),
            )
        )
        for i in range(g.num_vehicles):
            ids.append(f"{g.veh_id}_{i}")
            group.append(gi)
            initial.append(float(g.initial_speed))
    return VehicleTable(
        classes=tuple(classes),
        ids=ids,
        group=np.array(group, dtype=np.int64),
        start_edges=start.edges,
        start_lane_pos=start.lane_pos,
        start_lanes=start.lanes,
        initial_speeds=initial,
        routes=[_draw_route(spec, e, rng) for e in start.edges],
    )


def _draw_route(spec: NetworkSpec, edge: str, rng: np.random.Generator) -> str | None:
    """SUMO route id for a vehicle starting on ``edge`` (a seeded draw among choices)."""
    choices = spec.choices(edge)
    if len(choices) <= 1:
        return None
    probs = np.array([p for _, p in choices], dtype=np.float64)
    return route_name(edge, int(rng.choice(len(choices), p=probs / probs.sum())))


class FlowControllers:
    """Flow's per-vehicle controller objects (``k.vehicle.get_acc_controller(id)`` and co.).

    Acceleration controllers are per-vehicle views over the group's vectorised controller
    (kept per vehicle, so a stateful one keeps its memory between calls); lane-change and
    routing controllers are one object per group, as flowrun runs them, except Flow-style
    ones (``flow_style``), which are the vehicle's own object when its id is given.
    """

    def __init__(
        self, vehicles: VehicleParams, controls: list[GroupControl],
        flow_style: FlowStyleDriver | None = None,
    ) -> None:  # fmt: skip
        self._vehicles = vehicles
        self._controls = controls
        self._flow_style = flow_style
        self._views: dict[str, VehicleControllerView] = {}
        self._lane: dict[int, Any] = {}
        self._route: dict[int, Any] = {}

    def acceleration(self, veh_id: str, group: int) -> Any:
        """The vehicle's acceleration controller with Flow's ``get_action(env)`` (a Flow-style
        class's own object for that vehicle)."""
        ctrl = self._controls[group].controller
        if isinstance(ctrl, PerVehicleGroup):
            return ctrl.instance(veh_id)
        if veh_id not in self._views:
            g = self._vehicles.groups[group]
            self._views[veh_id] = VehicleControllerView(
                self._controls[group].controller, veh_id,
                car_following_params=g.car_following_params,
            )  # fmt: skip
        return self._views[veh_id]

    def lane_changing(self, group: int, veh_id: str | None = None) -> Any:
        """The group's lane-change controller (the vehicle's own for a Flow-style class)."""
        if self._flow_style is not None and veh_id is not None:
            own = self._flow_style.object_of(veh_id, group, "lane_change")
            if own is not None:
                return own
        if group not in self._lane:
            spec = self._vehicles.groups[group].lane_change_controller
            self._lane[group] = build_controller(spec.type, dict(spec.params))
        return self._lane[group]

    def routing(self, group: int, veh_id: str | None = None) -> Any:
        """The group's routing controller (``None`` without one; the vehicle's own for a
        Flow-style class)."""
        if self._flow_style is not None and veh_id is not None:
            own = self._flow_style.object_of(veh_id, group, "routing")
            if own is not None:
                return own
        if group not in self._route:
            spec = self._vehicles.groups[group].routing_controller
            self._route[group] = None if spec is None else build_controller(
                spec.type, dict(spec.params)
            )
        return self._route[group]
