"""Drivers built from an experiment's vehicle groups, above the controller registry.

:class:`FlowStyleDriver` runs the Flow-style (per-vehicle) lane-change and routing objects
of the groups whose classes are Flow-style; :class:`GroupRouters` runs the routers that
route a whole group at once (``route_vehicles``, e.g.
:class:`~flowrun.controllers.minicity_router.MinicityRouter`). Both resolve the groups'
controller names through :mod:`flowrun.controllers.registry`. ``vehicles`` is Flow's
``VehicleParams`` (anything with ``groups``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from flowrun.controllers.per_vehicle import PerVehicle, PerVehicleGroup
from flowrun.controllers.registry import build_controller, resolve_controller


def bind_per_vehicle_groups(controls: Sequence[Any], vehicles: Any) -> None:
    """Give each Flow-style group controller its vehicle type's car-following parameters.

    Args:
        controls: the groups' controls (``GroupControl``, one per ``vehicles.groups``).
        vehicles: the experiment's vehicle groups.
    """
    for group, control in zip(vehicles.groups, controls, strict=True):
        if isinstance(control.controller, PerVehicleGroup):
            control.controller.bind(group.car_following_params)


class FlowStyleDriver:
    """Runs the Flow-style lane-change and routing controllers of a set of vehicle groups.

    Args:
        vehicles: the experiment's vehicle groups; only groups whose lane-change or routing
            class is Flow-style are driven.
    """

    def __init__(self, vehicles: Any) -> None:
        self.lane_change: dict[int, PerVehicle] = {}
        self.routing: dict[int, PerVehicle] = {}
        for gi, g in enumerate(vehicles.groups):
            lc = g.lane_change_controller
            cls: Any = lc.cls or resolve_controller(lc.type)
            if getattr(cls, "per_vehicle", False):
                self.lane_change[gi] = PerVehicle(_lane_changer(cls, dict(lc.params)))
            rt = g.routing_controller
            if rt is not None:
                cls = rt.cls or resolve_controller(rt.type)
                if getattr(cls, "per_vehicle", False):
                    self.routing[gi] = PerVehicle(_router(cls, dict(rt.params)))

    def __bool__(self) -> bool:
        return bool(self.lane_change or self.routing)

    def clear(self) -> None:
        """Forget every vehicle's objects (at reset)."""
        for table in (*self.lane_change.values(), *self.routing.values()):
            table.clear()

    def object_of(self, veh_id: str, group: int, kind: str) -> Any:
        """The vehicle's ``"lane_change"`` or ``"routing"`` object, ``None`` if not Flow-style."""
        table = (self.lane_change if kind == "lane_change" else self.routing).get(group)
        return None if table is None else table.get(veh_id)

    def step(self, env: Any) -> None:
        """Flow's lane-change then routing actions of this step."""
        vk = env.k.vehicle
        pop = vk.table
        for gi, table in self.lane_change.items():
            ids = [pop.ids[r] for r in pop.rows_of_group(gi)]
            pairs = [(v, o.get_action(env)) for v, o in zip(ids, table.keep(ids), strict=True)]
            pairs = [(v, d) for v, d in pairs if d is not None]
            if pairs:
                vk.apply_lane_change([v for v, _ in pairs], direction=[d for _, d in pairs])
        for gi, table in self.routing.items():
            ids = [pop.ids[r] for r in pop.rows_of_group(gi)]
            routes = [o.choose_route(env) for o in table.keep(ids)]
            if any(r is not None for r in routes):
                vk.choose_routes(ids, routes)


def _lane_changer(cls: type, params: dict[str, Any]) -> Callable[[str], Any]:
    return lambda veh_id: cls(veh_id=veh_id, **params)


def _router(cls: type, params: dict[str, Any]) -> Callable[[str], Any]:
    return lambda veh_id: cls(veh_id=veh_id, router_params=params)


class GroupRouters:
    """Drives the routers that route a whole vehicle group at once (``route_vehicles``).

    Args:
        routers: ``(group index, router)`` pairs.
    """

    def __init__(self, routers: Sequence[tuple[int, Any]]) -> None:
        self.routers = list(routers)

    @classmethod
    def of(cls, vehicles: Any) -> GroupRouters:
        """The group routers of an experiment's vehicle groups (built from their specs)."""
        found = []
        for gi, g in enumerate(vehicles.groups):
            spec = g.routing_controller
            if spec is None:
                continue
            router_cls = spec.cls or resolve_controller(spec.type, "routing")
            if callable(getattr(router_cls, "route_vehicles", None)):
                found.append((gi, build_controller(router_cls, dict(spec.params), "routing")))
        return cls(found)

    def __bool__(self) -> bool:
        return bool(self.routers)

    def step(self, vk: Any, lanes: Any) -> None:
        """Reroute the cars that need it, at once (the kernel calls this at each update,
        before it looks for leaders along the routes)."""
        for gi, router in self.routers:
            rows, routes = router.route_vehicles(vk, lanes, vk.table.rows_of_group(gi), vk.rng)
            if rows:
                vk.reroute_now(rows, routes)
