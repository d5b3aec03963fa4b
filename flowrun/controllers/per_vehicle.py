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
noise and fail-safes, :func:`~flowrun.controllers.view.flow_action`), then the lane changes,
then the routes are applied (:class:`~flowrun.controllers.drivers.FlowStyleDriver`).
flowrun's built-in controllers keep their vectorised path; this one costs a Python call per
vehicle and step, as in Flow.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from flowrun.controllers.base import AccelerationController
from flowrun.types import CarFollowingInputs, FloatArray


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
