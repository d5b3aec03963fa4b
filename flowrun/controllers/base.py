"""Controller contract: pure, vectorised formulas over arrays of vehicle state.

A controller object drives one *group* of vehicles (one ``VehicleParams.add`` call). Every
step the kernel hands it a :class:`CarFollowingInputs` with one entry per vehicle of the group
(always in the same order) and gets back one acceleration per vehicle, in m/s^2. Nothing here
knows about SUMO or the environment, so every formula is testable with plain numbers.

A controller that gives no command (:class:`~flowrun.controllers.rl.RLController`,
:class:`~flowrun.controllers.rl.SimCarFollowingController`) returns ``nan`` for every vehicle;
its class attributes ``is_rl`` / ``commands_sumo`` say so up front.
"""

from __future__ import annotations

import functools
import inspect
import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, ClassVar

import numpy as np

from flowrun.controllers.fail_safe import apply_fail_safes, check_fail_safe
from flowrun.controllers.limits import DEFAULT_MAX_ACCEL, DEFAULT_MAX_DECEL, vehicle_limits
from flowrun.controllers.params import (
    Param,
    ParameterValueError,
    anything,
    check_params,
)
from flowrun.controllers.view import flow_action, read_inputs
from flowrun.types import CarFollowingInputs, FloatArray

#: Flow's ``fail_safe`` argument: a name, a list of names, or ``None``.
FailSafe = str | Sequence[str] | None


def make_inputs(
    speed: Sequence[float] | FloatArray,
    headway: Sequence[float] | FloatArray,
    leader_speed: Sequence[float] | FloatArray | None = None,
    *,
    follower_headway: Sequence[float] | FloatArray | None = None,
    follower_speed: Sequence[float] | FloatArray | None = None,
    speed_limit: float | Sequence[float] | FloatArray = 30.0,
    dt: float = 0.1,
    time: float = 0.0,
    max_accel: float | Sequence[float] | FloatArray | None = None,
    max_decel: float | Sequence[float] | FloatArray | None = None,
) -> CarFollowingInputs:
    """Build :class:`CarFollowingInputs` from lists, filling the contract's defaults.

    Missing leader speeds (or those of vehicles without a leader) become the ego speed;
    a missing follower gives ``inf`` headway and the ego speed. Scalars broadcast.
    """
    v = np.asarray(speed, dtype=np.float64).reshape(-1)
    n = v.shape[0]

    def arr(x: float | Sequence[float] | FloatArray, name: str) -> FloatArray:
        try:
            return np.broadcast_to(np.asarray(x, dtype=np.float64), (n,)).copy()
        except ValueError as exc:
            raise ValueError(f"{name} must have {n} entries (one per vehicle)") from exc

    h = arr(headway, "headway")
    vl = v.copy() if leader_speed is None else arr(leader_speed, "leader_speed")
    vl = np.where(np.isfinite(h), vl, v)
    fh = np.full(n, np.inf) if follower_headway is None else arr(follower_headway, "fh")
    fv = v.copy() if follower_speed is None else arr(follower_speed, "follower_speed")
    fv = np.where(np.isfinite(fh), fv, v)
    return CarFollowingInputs(
        speed=v,
        headway=h,
        leader_speed=vl,
        follower_headway=fh,
        follower_speed=fv,
        speed_limit=arr(speed_limit, "speed_limit"),
        dt=float(dt),
        time=float(time),
        max_accel=None if max_accel is None else arr(max_accel, "max_accel"),
        max_decel=None if max_decel is None else arr(max_decel, "max_decel"),
    )


def _veh_id(owner: str, name: str, value: Any) -> str | None:
    if value is not None and not isinstance(value, str):
        raise ParameterValueError(
            f"{owner}: {name} must be a vehicle id string, got {value!r}", name
        )
    return value


#: The parameters every acceleration controller takes (Flow's ``BaseController``); a
#: built-in declares them among its own, in Flow's order, with :func:`declared`.
VEH_ID = Param("veh_id", None, "", "Flow's vehicle id", convert=_veh_id)
CAR_FOLLOWING_PARAMS = Param(
    "car_following_params", None, "", "the vehicle type's SumoCarFollowingParams",
    convert=anything,
)  # fmt: skip
TIME_DELAY = Param("time_delay", 0.0, "s", "reaction delay of the safe_velocity fail-safe", low=0)
NOISE = Param("noise", 0.0, "m/s^2", "std of the acceleration noise (times sqrt(dt))", low=0)
FAIL_SAFE = Param(
    "fail_safe", None, "", "fail-safe name(s) run on each command",
    convert=lambda owner, name, value: check_fail_safe(value),
)  # fmt: skip
DISPLAY_WARNINGS = Param(
    "display_warnings", True, "", "accepted for Flow (flowrun never prints)",
    convert=lambda owner, name, value: bool(value),
)  # fmt: skip
BASE_PARAMS = (VEH_ID, CAR_FOLLOWING_PARAMS, TIME_DELAY, FAIL_SAFE, NOISE, DISPLAY_WARNINGS)


@functools.lru_cache(maxsize=16)
def _sqrt_of(dt: float) -> FloatArray:
    """``sqrt(dt)`` as a 0-d float64 array (a ufunc converts a Python float operand at every
    call; the same value)."""
    return np.array(math.sqrt(dt))


class AccelerationController:
    """Base of all acceleration controllers.

    Subclasses implement :meth:`_accel` (the formula). :meth:`get_accel` adds Flow's Gaussian
    acceleration noise, ``sqrt(dt) * N(0, noise)``, drawn from the generator it is given, then
    runs the requested fail-safes (see :mod:`flowrun.controllers.fail_safe`).

    The constructor is Flow's ``BaseController(veh_id, car_following_params, delay=0,
    fail_safe=None, noise=0, display_warnings=True)``. When the kernel's inputs carry no
    ``max_accel`` / ``max_decel``, the limits of ``car_following_params`` are used instead.

    **Built-in controllers** are dataclasses over this base: their fields are their
    constructor's arguments in Flow's order, each declared once with its default, unit and
    bounds (:mod:`flowrun.controllers.params`); the shared ones are :data:`BASE_PARAMS`.
    The generated constructor ends in :meth:`__post_init__`, which checks them all.

    **Flow-style controllers.** A subclass that implements Flow's per-vehicle
    ``get_accel(self, env)`` instead of ``_accel`` is a *per-vehicle* controller
    (``per_vehicle = True``): the environment makes one object per vehicle, as Flow does,
    and calls Flow's :meth:`get_action` on each every step (noise and fail-safes applied as
    Flow applies them). The built-in vectorised controllers stay the fast path.

    Args:
        veh_id: Flow's vehicle id (informative for a vectorised controller, which drives a
            whole group).
        car_following_params: the vehicle type's car-following parameters, or ``None``.
        delay: reaction delay used by the ``safe_velocity`` fail-safe, s (keyword
            ``time_delay`` is the same).
        fail_safe: Flow's fail-safe name(s): ``instantaneous``, ``safe_velocity``,
            ``feasible_accel``, ``obey_speed_limit`` (or a list of them), or ``None``.
        noise: standard deviation of the acceleration noise, m/s^2 per sqrt(s).
        display_warnings: accepted for Flow compatibility (flowrun never prints).
        time_delay: flowrun's keyword for ``delay``.

    Attributes:
        registered_name: the name configs use (``type: IDM``).
        commands_sumo: ``False`` for controllers that leave the car to SUMO's own model.
        is_rl: ``True`` for the RL agent's placeholder.
        stateful: ``True`` when the controller keeps per-vehicle memory between steps.
    """

    registered_name: ClassVar[str] = ""
    aliases: ClassVar[tuple[str, ...]] = ()
    commands_sumo: ClassVar[bool] = True
    is_rl: ClassVar[bool] = False
    stateful: ClassVar[bool] = False
    #: ``True`` for a Flow-style subclass whose ``get_accel(env)`` drives one vehicle
    per_vehicle: ClassVar[bool] = False

    veh_id: str | None = None
    car_following_params: Any = None
    time_delay: float = 0.0
    noise: float = 0.0
    fail_safe: FailSafe = ()
    display_warnings: bool = True

    def __init__(
        self,
        veh_id: str | None = None,
        car_following_params: Any = None,
        delay: float = 0.0,
        fail_safe: FailSafe = None,
        noise: float = 0.0,
        display_warnings: bool = True,
        *,
        time_delay: float | None = None,
    ) -> None:
        self.veh_id = veh_id
        self.car_following_params = car_following_params
        self.time_delay = delay if time_delay is None else time_delay
        self.fail_safe = fail_safe
        self.noise = noise
        self.display_warnings = display_warnings
        self.__post_init__()

    def __post_init__(self) -> None:
        """Check the declared parameters (see :mod:`flowrun.controllers.params`)."""
        check_params(self, BASE_PARAMS)
        #: the fail-safes run on every command, in order
        self.fail_safes: tuple[str, ...] = check_fail_safe(self.fail_safe)
        self._limits = vehicle_limits(self.car_following_params)

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.per_vehicle = takes_env_only(cls.get_accel)

    @property
    def delay(self) -> float:
        """Flow's name of :attr:`time_delay` (s)."""
        return self.time_delay

    @property
    def accel_noise(self) -> float:
        """Flow's name of :attr:`noise` (m/s^2 per sqrt(s))."""
        return self.noise

    @property
    def max_accel(self) -> float:
        """Flow's ``max_accel``: the vehicle type's ``accel`` (m/s^2; 2.6 when unknown)."""
        return self._limits[0] if self._limits is not None else DEFAULT_MAX_ACCEL

    @property
    def max_deaccel(self) -> float:
        """Flow's ``max_deaccel``: the vehicle type's ``decel`` (m/s^2, positive; 7.5 unknown)."""
        return self._limits[1] if self._limits is not None else DEFAULT_MAX_DECEL

    def with_limits(self, inputs: CarFollowingInputs) -> CarFollowingInputs:
        """``inputs`` with this controller's vehicle limits filled in where the kernel gave none."""
        if self._limits is None or (inputs.max_accel is not None and inputs.max_decel is not None):
            return inputs
        n = inputs.size
        return replace(
            inputs,
            max_accel=np.full(n, self._limits[0]) if inputs.max_accel is None else inputs.max_accel,
            max_decel=np.full(n, self._limits[1]) if inputs.max_decel is None else inputs.max_decel,
        )

    def reset(self, num_vehicles: int) -> None:
        """Forget any per-vehicle memory; called at every environment reset."""

    def get_accel(self, inputs: CarFollowingInputs, rng: np.random.Generator) -> FloatArray:
        """Accelerations (m/s^2) for every vehicle of the group, noise included.

        ``nan`` entries mean "no command this step" (leave the vehicle to SUMO / the agent).
        """
        if inputs.max_accel is None or inputs.max_decel is None:
            inputs = self.with_limits(inputs)
        accel = np.asarray(self._accel(inputs), dtype=np.float64)
        if self.is_rl or not self.commands_sumo:
            return accel
        if self.noise > 0:
            accel = accel + _sqrt_of(inputs.dt) * rng.normal(0.0, self.noise, inputs.size)
        if self.fail_safes:
            accel = apply_fail_safes(self.fail_safes, accel, inputs, self.time_delay)
        return accel

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        raise NotImplementedError(
            f"{type(self).__name__} implements neither flowrun's _accel(inputs) nor Flow's "
            "get_accel(env)"
        )

    # ------------------------------------------------------------- Flow's fail-safe helpers
    def _one(self, env: Any) -> CarFollowingInputs:
        if self.veh_id is None:
            raise ValueError(f"{type(self).__name__}: Flow's per-vehicle helpers need veh_id")
        return read_inputs(env, self.veh_id, self.max_accel, self.max_deaccel)

    def _safe(self, name: str, env: Any, action: float) -> float:
        out = apply_fail_safes((name,), np.array([float(action)]), self._one(env), self.time_delay)
        return float(out[0])

    def get_safe_action_instantaneous(self, env: Any, action: float) -> float:
        """Flow's helper: ``action`` after the ``instantaneous`` fail-safe, m/s^2."""
        return self._safe("instantaneous", env, action)

    def get_safe_velocity_action(self, env: Any, action: float) -> float:
        """Flow's helper: ``action`` after the ``safe_velocity`` fail-safe, m/s^2."""
        return self._safe("safe_velocity", env, action)

    def get_obey_speed_limit_action(self, env: Any, action: float) -> float:
        """Flow's helper: ``action`` after the ``obey_speed_limit`` fail-safe, m/s^2."""
        return self._safe("obey_speed_limit", env, action)

    def get_feasible_action(self, action: float) -> float:
        """Flow's helper: ``action`` clipped to ``[-max_deaccel, max_accel]``, m/s^2."""
        return float(min(max(float(action), -self.max_deaccel), self.max_accel))

    def safe_velocity(self, env: Any) -> float:
        """Flow's safe velocity of this vehicle, m/s: ``2*h/dt + (v_lead - v) - 2*v*delay``
        (``inf`` without a leader)."""
        x = self._one(env)
        v = float(x.speed[0])
        return float(
            2 * x.headway[0] / x.dt + (x.leader_speed[0] - v) - 2 * v * self.time_delay
        )

    def get_action(self, env: Any) -> float | None:
        """Flow's ``get_action(env)``: this vehicle's acceleration with noise and fail-safes
        (m/s^2), or ``None`` when SUMO drives it this step (see
        :func:`flowrun.controllers.view.flow_action`)."""
        return flow_action(self, env)


def takes_env_only(method: Any) -> bool:
    """Whether ``method`` is Flow's per-vehicle form ``f(self, env)`` (one argument besides
    ``self``), as opposed to flowrun's vectorised ``f(self, inputs, rng)``."""
    try:
        params = list(inspect.signature(method).parameters.values())
    except (TypeError, ValueError):
        return False
    positional = [p for p in params[1:] if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    required = [p for p in positional if p.default is p.empty]
    return len(positional) == 1 and len(required) == 1
