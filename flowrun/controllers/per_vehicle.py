"""Flow-style controllers written per vehicle, driven as Flow drives them.

Flow code defines controllers that look at the whole environment for one vehicle:

- an acceleration controller subclasses ``BaseController`` and implements
  ``get_accel(self, env)`` (returning m/s^2, or ``None`` to leave the car to SUMO);
- a routing controller subclasses ``BaseRouter`` and implements ``choose_route(self, env)``
  (returning a list of edges, or ``None`` to keep the route);
- a lane-change controller subclasses ``BaseLaneChangeController`` and implements
  ``get_lane_change_action(self, env)`` (returning ``-1``, ``0`` or ``1``).

Given in ``VehicleParams.add(...)``, each vehicle of the group gets its own object, made with
Flow's constructor call (``Cls(veh_id, car_following_params=..., **params)``,
``Cls(veh_id=..., router_params=params)``, ``Cls(veh_id=..., **params)``), kept while the
vehicle is in the network. Every simulation step, in Flow's order, the accelerations (with
noise and fail-safes, :func:`flow_action`), then the lane changes, then the routes are
applied. flowrun's built-in controllers keep their vectorised path; this one costs a Python
call per vehicle and step, as in Flow.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from flowrun.controllers.base import AccelerationController
from flowrun.controllers.fail_safe import apply_fail_safes
from flowrun.types import CarFollowingInputs, FloatArray

if TYPE_CHECKING:
    from flowrun.config.params import VehicleParams


def controller_rng(env: Any) -> np.random.Generator:
    """The generator for Flow's acceleration noise: the env's controller generator (seeded
    by ``reset``), else ``env.np_random``, else a fresh one."""
    for name in ("controller_rng", "np_random"):
        rng = getattr(env, name, None)
        if isinstance(rng, np.random.Generator):
            return rng
    return np.random.default_rng()


def flow_action(controller: AccelerationController, env: Any) -> float | None:
    """Flow's ``BaseController.get_action(env)`` for one vehicle (``controller.veh_id``).

    ``None`` (SUMO drives the car this step) on no edge or a junction-internal edge, or when
    ``get_accel`` gives ``None``. Otherwise noise ``sqrt(dt) * N(0, noise)`` is added, then
    the fail-safes run in the listed order, as in Flow. A vectorised (built-in) controller
    answers through a :class:`~flowrun.controllers.view.VehicleControllerView` of itself.

    Raises:
        ValueError: the controller has no ``veh_id``.
    """
    veh_id = controller.veh_id
    if veh_id is None:
        raise ValueError(
            f"{type(controller).__name__}.get_action(env) needs the controller's veh_id; "
            "create it as Flow does: Controller(veh_id, car_following_params=...)"
        )
    if not controller.per_vehicle:
        from flowrun.controllers.view import VehicleControllerView

        view = controller.__dict__.get("_flow_view")
        if view is None or view.veh_id != veh_id:
            view = VehicleControllerView(controller, veh_id)
            controller.__dict__["_flow_view"] = view
        return view.get_action(env)
    edge = env.k.vehicle.get_edge(veh_id)
    if not edge or edge[0] == ":":
        return None
    accel = controller.get_accel(env)  # type: ignore[call-arg]
    if accel is None:
        return None
    value = float(accel)
    if controller.noise > 0:
        dt = float(getattr(env, "sim_step", None) or env.sim_params.sim_step)
        value += math.sqrt(dt) * float(controller_rng(env).normal(0.0, controller.noise))
    if controller.fail_safe:
        from flowrun.controllers.view import read_inputs

        inputs = read_inputs(env, veh_id, controller.max_accel, controller.max_deaccel)
        value = float(
            apply_fail_safes(
                controller.fail_safe, np.array([value]), inputs, controller.time_delay
            )[0]
        )
    return value


class PerVehicle:
    """One controller object per vehicle of a group, made on first use by ``factory(veh_id)``.

    Objects of vehicles that left the network are dropped by :meth:`keep`.
    """

    def __init__(self, factory: Callable[[str], Any]) -> None:
        self._factory = factory
        self.objects: dict[str, Any] = {}

    def get(self, veh_id: str) -> Any:
        """The vehicle's controller object (made now if it has none yet)."""
        obj = self.objects.get(veh_id)
        if obj is None:
            obj = self.objects[veh_id] = self._factory(veh_id)
        return obj

    def keep(self, veh_ids: Sequence[str]) -> list[Any]:
        """The objects of ``veh_ids`` in that order; every other vehicle's is dropped."""
        objs = [self.get(v) for v in veh_ids]
        if len(self.objects) != len(objs):
            self.objects = dict(zip(veh_ids, objs, strict=True))
        return objs

    def clear(self) -> None:
        """Forget every object (a new episode makes new ones, as Flow re-adds its cars)."""
        self.objects = {}


class PerVehicleGroup(AccelerationController):
    """The acceleration controller of a group whose class is Flow-style (``per_vehicle``).

    Holds one object of the user's class per vehicle and answers, for the environment's
    step, one acceleration per vehicle (``nan``: no command) from their ``get_action(env)``.

    Args:
        cls: the user's controller class.
        params: its keyword parameters (Flow's ``acceleration_controller[1]``).
        car_following_params: the vehicle type's ``SumoCarFollowingParams`` (see
            :meth:`bind`).
    """

    #: the users' objects may keep memory between steps (and no vectorised formula exists)
    stateful = True

    def __init__(
        self, cls: type[AccelerationController], params: dict[str, Any],
        car_following_params: Any = None,
    ) -> None:  # fmt: skip
        super().__init__(car_following_params=car_following_params)
        self.cls = cls
        self.params = dict(params)
        self.vehicles = PerVehicle(self._make)

    def __repr__(self) -> str:
        return f"PerVehicleGroup({self.cls.__name__}, {self.params!r})"

    def _make(self, veh_id: str) -> AccelerationController:
        return self.cls(veh_id, car_following_params=self.car_following_params, **self.params)

    def bind(self, car_following_params: Any) -> None:
        """Use the vehicle type's car-following parameters for the objects made from now."""
        self.car_following_params = car_following_params
        self.vehicles.clear()

    def instance(self, veh_id: str) -> AccelerationController:
        """The vehicle's own controller object (Flow's ``get_acc_controller(veh_id)``)."""
        obj: AccelerationController = self.vehicles.get(veh_id)
        return obj

    def actions(self, env: Any, veh_ids: Sequence[str]) -> FloatArray:
        """One acceleration per vehicle of ``veh_ids`` (m/s^2; ``nan``: no command)."""
        out = np.empty(len(veh_ids))
        for i, obj in enumerate(self.vehicles.keep(veh_ids)):
            a = obj.get_action(env)
            out[i] = math.nan if a is None else a
        return out

    def reset(self, num_vehicles: int) -> None:
        """At an episode's start (``0``) forget every object; otherwise keep the objects of
        the vehicles still there (:meth:`actions` drops the others)."""
        if num_vehicles == 0:
            self.vehicles.clear()

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        return np.full(inputs.size, np.nan)  # driven through :meth:`actions`, never here


def bind_per_vehicle_groups(controls: Sequence[Any], vehicles: VehicleParams) -> None:
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

    def __init__(self, vehicles: VehicleParams) -> None:
        from flowrun.controllers.registry import resolve_controller

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
