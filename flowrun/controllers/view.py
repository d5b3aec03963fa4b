"""Flow's per-vehicle controller objects, as thin views over flowrun's vectorised controllers.

Flow code asks ``env.k.vehicle.get_acc_controller(veh_id).get_action(env)``. flowrun drives a
whole vehicle group with one vectorised controller; :class:`VehicleControllerView` binds such
a controller to one vehicle id and answers Flow's per-vehicle calls by reading that vehicle's
state through ``env.k.vehicle`` getters (one vehicle, so this path is for Flow code and tests;
the kernel's own step stays vectorised).

A stateful controller (:class:`~flowrun.controllers.velocity.PISaturation`) gets its own copy
in the view, so the view's calls never disturb the group's memory; keep one view per vehicle
to keep its memory from step to step, as Flow keeps one controller per vehicle.
:func:`flow_action` is Flow's ``get_action(env)`` of any controller object, the per-vehicle
(Flow-style) ones included. This module sits below the controller contract
(:mod:`flowrun.controllers.base`), whose Flow helper methods call it.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

from flowrun.controllers.fail_safe import apply_fail_safes
from flowrun.controllers.limits import DEFAULT_MAX_ACCEL, DEFAULT_MAX_DECEL, vehicle_limits
from flowrun.types import CarFollowingInputs

#: Distance to the end of its edge (m) within which FollowerStopper gives no command on a
#: ``danger_edges`` edge (Flow).
DANGER_DISTANCE = 10.0


def _sim_step(env: Any) -> float:
    """Flow's ``env.sim_step`` (s), or ``env.sim_params.sim_step``."""
    dt = getattr(env, "sim_step", None)
    if dt is None:
        dt = env.sim_params.sim_step
    return float(dt)


def _sim_time(env: Any) -> float:
    """Simulation time (s) if the env exposes it, else 0."""
    sim: Any = getattr(getattr(env, "k", None), "simulation", None)
    time = getattr(sim, "time", None)
    if time is None and hasattr(sim, "get_time"):
        time = sim.get_time()
    try:
        return float(time) if time is not None else 0.0
    except (TypeError, ValueError):
        return 0.0


def _speed_limit(env: Any, edge: str) -> float:
    """Speed limit of ``edge`` (m/s) from ``env.k.network.speed_limit``; ``inf`` if unknown."""
    network = getattr(env.k, "network", None)
    if network is None or not hasattr(network, "speed_limit") or not edge:
        return math.inf
    try:
        return float(network.speed_limit(edge))
    except (KeyError, ValueError, TypeError):
        return math.inf


def _length(vk: Any, veh_id: str) -> np.ndarray | None:
    """The vehicle's length (m) if the kernel tells it."""
    get_length = getattr(vk, "get_length", None)
    return None if get_length is None else np.array([float(get_length(veh_id))])


def read_inputs(
    env: Any, veh_id: str, max_accel: float, max_decel: float
) -> CarFollowingInputs:
    """One vehicle's :class:`CarFollowingInputs`, read through ``env.k.vehicle`` getters.

    Args:
        env: the environment (Flow's ``env``).
        veh_id: the vehicle.
        max_accel: its maximum acceleration, m/s^2.
        max_decel: its maximum deceleration, m/s^2 (positive).
    """
    vk = env.k.vehicle
    v = float(vk.get_speed(veh_id))
    lead = vk.get_leader(veh_id)
    if lead:
        h, v_lead = float(vk.get_headway(veh_id)), float(vk.get_speed(lead))
    else:
        h, v_lead = math.inf, v
    follower = vk.get_follower(veh_id)
    if follower:
        h_f, v_f = float(vk.get_headway(follower)), float(vk.get_speed(follower))
    else:
        h_f, v_f = math.inf, v
    edge = vk.get_edge(veh_id)
    return CarFollowingInputs(
        speed=np.array([v]),
        headway=np.array([h]),
        leader_speed=np.array([v_lead]),
        follower_headway=np.array([h_f]),
        follower_speed=np.array([v_f]),
        speed_limit=np.array([_speed_limit(env, edge)]),
        dt=_sim_step(env),
        time=_sim_time(env),
        max_accel=np.array([max_accel]),
        max_decel=np.array([max_decel]),
        length=_length(vk, veh_id),
    )


class VehicleControllerView:
    """One vehicle's acceleration controller, with Flow's ``BaseController`` interface.

    Args:
        controller: the vectorised controller of the vehicle's group.
        veh_id: the vehicle's id.
        car_following_params: the vehicle type's ``SumoCarFollowingParams``; its ``accel`` /
            ``decel`` are the limits Flow's controllers use. Defaults to the controller's own
            ``car_following_params``, then to Flow's defaults (2.6 and 7.5 m/s^2).
        rng: generator for the acceleration noise; by default ``env.np_random`` when the
            env has one, else a generator owned by the view.

    Attributes:
        veh_id: the vehicle's id.
        controller: the controller the view calls (a private copy for stateful ones).
        car_following_params: as given (or the controller's).
        max_accel: the vehicle's maximum acceleration, m/s^2.
        max_deaccel: the vehicle's maximum deceleration, m/s^2 (positive).
    """

    def __init__(
        self,
        controller: Any,
        veh_id: str,
        car_following_params: Any = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        if controller.stateful:
            controller = copy.deepcopy(controller)
            controller.reset(1)
        self.controller = controller
        self.veh_id = veh_id
        self.car_following_params = (
            car_following_params
            if car_following_params is not None
            else controller.car_following_params
        )
        limits = vehicle_limits(self.car_following_params)
        self.max_accel, self.max_deaccel = limits or (DEFAULT_MAX_ACCEL, DEFAULT_MAX_DECEL)
        self._rng = rng

    def __repr__(self) -> str:
        return f"{type(self).__name__}({type(self.controller).__name__}, {self.veh_id!r})"

    def __getattr__(self, name: str) -> Any:
        # Flow code reads controller parameters directly (``v_des``, ``fail_safe``, ...).
        if name.startswith("__") or name == "controller":
            raise AttributeError(name)
        return getattr(self.controller, name)

    @property
    def sumo_controller(self) -> bool:
        """Whether SUMO's own model drives the vehicle (Flow's ``uses_sumo``)."""
        return not self.controller.commands_sumo

    def uses_sumo(self) -> bool:
        """Flow's name for :attr:`sumo_controller`."""
        return self.sumo_controller

    def inputs(self, env: Any) -> CarFollowingInputs:
        """The one-vehicle :class:`CarFollowingInputs` read from ``env.k.vehicle``."""
        return read_inputs(env, self.veh_id, self.max_accel, self.max_deaccel)

    def _generator(self, env: Any) -> np.random.Generator:
        if self._rng is not None:
            return self._rng
        rng = getattr(env, "np_random", None)
        if isinstance(rng, np.random.Generator):
            return rng
        self._rng = np.random.default_rng()
        return self._rng

    def get_accel(self, env: Any) -> float | None:
        """The controller's formula alone (no noise, no fail-safe), m/s^2; ``None``: no command.

        As in Flow, a stateful controller advances its memory on every call.
        """
        value = float(self.controller._accel(self.inputs(env))[0])
        return None if math.isnan(value) else value

    def get_action(self, env: Any) -> float | None:
        """Flow's ``get_action``: the acceleration with noise and fail-safes, m/s^2.

        ``None`` (SUMO drives this step) on no edge or a junction-internal edge (id starting
        with ``:``), for the RL and SUMO placeholders, and where FollowerStopper hands the
        car back (near the end of a ``danger_edges`` edge, outside ``control_length``).
        """
        edge = env.k.vehicle.get_edge(self.veh_id)
        if not edge or edge[0] == ":" or self._handed_back(env, edge):
            return None
        value = float(self.controller.get_accel(self.inputs(env), self._generator(env))[0])
        return None if math.isnan(value) else value

    def find_intersection_dist(self, env: Any) -> float:
        """Distance (m) to the end of the vehicle's edge (:func:`intersection_distance`)."""
        return intersection_distance(env, self.veh_id)

    def _handed_back(self, env: Any, edge: str) -> bool:
        danger = getattr(self.controller, "danger_edges", None)
        if danger and edge in danger and self.find_intersection_dist(env) <= DANGER_DISTANCE:
            return True
        control = getattr(self.controller, "control_length", None)
        if control:
            x = float(env.k.vehicle.get_x_by_id(self.veh_id))
            return bool(x < control[0] or x > control[1])
        return False


def intersection_distance(env: Any, veh_id: str) -> float:
    """Flow's ``find_intersection_dist``: the distance (m) from the car to the end of its edge;
    ``-10`` without an edge, 0 on an edge whose id contains ``center`` (a grid junction)."""
    edge = env.k.vehicle.get_edge(veh_id)
    if not edge:
        return -10.0
    if "center" in edge:
        return 0.0
    return float(env.k.network.edge_length(edge)) - float(env.k.vehicle.get_position(veh_id))


def controller_rng(env: Any) -> np.random.Generator:
    """The generator for Flow's acceleration noise: the env's controller generator (seeded
    by ``reset``), else ``env.np_random``, else a fresh one."""
    for name in ("controller_rng", "np_random"):
        rng = getattr(env, name, None)
        if isinstance(rng, np.random.Generator):
            return rng
    return np.random.default_rng()


def flow_action(controller: Any, env: Any) -> float | None:
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
        view = controller.__dict__.get("_flow_view")
        if view is None or view.veh_id != veh_id:
            view = VehicleControllerView(controller, veh_id)
            controller.__dict__["_flow_view"] = view
        return view.get_action(env)
    edge = env.k.vehicle.get_edge(veh_id)
    if not edge or edge[0] == ":":
        return None
    accel = controller.get_accel(env)
    if accel is None:
        return None
    value = float(accel)
    if controller.noise > 0:
        dt = float(getattr(env, "sim_step", None) or env.sim_params.sim_step)
        value += math.sqrt(dt) * float(controller_rng(env).normal(0.0, controller.noise))
    if controller.fail_safes:
        inputs = read_inputs(env, veh_id, controller.max_accel, controller.max_deaccel)
        value = float(
            apply_fail_safes(
                controller.fail_safes, np.array([value]), inputs, controller.time_delay
            )[0]
        )
    return value
