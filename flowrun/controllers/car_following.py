"""Car-following controllers: the classes binding the pure formulas of
:mod:`flowrun.controllers.car_following_formulas` (re-exported here) to vehicle groups.

Conventions (see :class:`~flowrun.controllers.base.CarFollowingInputs`): ``h`` is the
bumper-to-bumper gap to the leader in m (``inf`` without a leader), speeds are in m/s.

Without a leader, Flow's CFM, BCM and OVM controllers (and Bando-FTL with
``want_max_accel=True``) command the vehicle type's maximum acceleration; the classes here do
the same, using ``inputs.max_accel`` (the vehicle type's ``accel``, filled by the kernel or
from the controller's ``car_following_params``) or, when neither is known, SUMO's default
2.6 m/s^2.

Each class declares its parameters once, as dataclass fields in the order of Flow's
constructor (name, default, unit, bounds: :mod:`flowrun.controllers.params`), so
``IDMController("human_0", car_following_params=...)`` works as in Flow.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from flowrun.controllers.base import (
    CAR_FOLLOWING_PARAMS,
    DEFAULT_MAX_ACCEL,
    DISPLAY_WARNINGS,
    FAIL_SAFE,
    NOISE,
    TIME_DELAY,
    VEH_ID,
    AccelerationController,
    FailSafe,
)
from flowrun.controllers.car_following_formulas import (
    bando_ftl_accel,
    bcm_accel,
    cfm_accel,
    gipps_accel,
    idm_accel,
    linear_ovm_accel,
    ovm_accel,
)
from flowrun.controllers.params import declared, flag, option, param
from flowrun.flow_values import FLOW_ERROR, FLOW_NO_GAP
from flowrun.types import CarFollowingInputs, FloatArray

#: Gipps' decelerations are negative numbers, as in Flow
_NEGATIVE = "a negative deceleration"


def _free_road(inputs: CarFollowingInputs, accel: FloatArray) -> FloatArray:
    """Replace the command of vehicles without a leader by their maximum acceleration."""
    max_accel = inputs.max_accel if inputs.max_accel is not None else DEFAULT_MAX_ACCEL
    return np.where(inputs.has_leader, accel, max_accel)


@dataclass(eq=False)
class IDMController(AccelerationController):
    """Intelligent Driver Model (see :func:`idm_accel`); Flow's defaults."""

    registered_name = "IDM"

    veh_id: str | None = declared(VEH_ID)
    v0: float = param(30, "m/s", "desired speed", low=0, strict=True, allow_inf=True)
    T: float = param(1, "s", "desired time headway", low=0)
    a: float = param(1, "m/s^2", "maximum acceleration", low=0, strict=True)
    b: float = param(1.5, "m/s^2", "comfortable deceleration", low=0, strict=True)
    delta: float = param(4, "", "acceleration exponent", low=0, strict=True)
    s0: float = param(2, "m", "minimum gap", low=0)
    time_delay: float = declared(TIME_DELAY)
    noise: float = declared(NOISE)
    fail_safe: FailSafe = declared(FAIL_SAFE)
    display_warnings: bool = declared(DISPLAY_WARNINGS)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        return idm_accel(
            inputs.speed, inputs.headway, inputs.leader_speed,
            v0=self.v0, T=self.T, a=self.a, b=self.b, delta=self.delta, s0=self.s0,
        )  # fmt: skip


@dataclass(eq=False)
class CFMController(AccelerationController):
    """Linear car-following model (see :func:`cfm_accel`); max accel without a leader."""

    registered_name = "CFM"

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)
    k_d: float = param(1, "1/s^2", "gain on the gap error", low=0)
    k_v: float = param(1, "1/s", "gain on the speed difference to the leader", low=0)
    k_c: float = param(1, "1/s", "gain on the error to the desired speed", low=0)
    d_des: float = param(1, "m", "desired gap", low=0)
    v_des: float = param(8, "m/s", "desired speed", low=0)
    time_delay: float = declared(TIME_DELAY)
    noise: float = declared(NOISE)
    fail_safe: FailSafe = declared(FAIL_SAFE)
    display_warnings: bool = declared(DISPLAY_WARNINGS)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        h = np.where(inputs.has_leader, inputs.headway, 0.0)
        accel = cfm_accel(
            inputs.speed, h, inputs.leader_speed,
            k_d=self.k_d, k_v=self.k_v, k_c=self.k_c, d_des=self.d_des, v_des=self.v_des,
        )  # fmt: skip
        return _free_road(inputs, accel)


class BCMController(CFMController):
    """Bilateral control model (see :func:`bcm_accel`); max accel without a leader."""

    registered_name = "BCM"

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        accel = bcm_accel(
            inputs.speed, inputs.headway, inputs.leader_speed,
            inputs.follower_headway, inputs.follower_speed,
            k_d=self.k_d, k_v=self.k_v, k_c=self.k_c, v_des=self.v_des,
        )  # fmt: skip
        return _free_road(inputs, accel)


@dataclass(eq=False)
class OVMController(AccelerationController):
    """Optimal Velocity Model (see :func:`ovm_accel`); max accel without a leader."""

    registered_name = "OVM"

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)
    alpha: float = param(1, "1/s", "gain on the optimal-velocity error", low=0)
    beta: float = param(1, "1/s", "gain on the speed difference to the leader", low=0)
    h_st: float = param(2, "m", "gap below which the optimal velocity is 0", low=0)
    h_go: float = param(15, "m", "gap above which it is v_max", low="h_st", strict=True)
    v_max: float = param(30, "m/s", "maximum desired speed", low=0)
    time_delay: float = declared(TIME_DELAY)
    noise: float = declared(NOISE)
    fail_safe: FailSafe = declared(FAIL_SAFE)
    display_warnings: bool = declared(DISPLAY_WARNINGS)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        accel = ovm_accel(
            inputs.speed, inputs.headway, inputs.leader_speed,
            alpha=self.alpha, beta=self.beta, h_st=self.h_st, h_go=self.h_go, v_max=self.v_max,
        )  # fmt: skip
        return _free_road(inputs, accel)


@dataclass(eq=False)
class LinearOVM(AccelerationController):
    """Linear optimal-velocity model (see :func:`linear_ovm_accel`)."""

    registered_name = "LinearOVM"

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)
    v_max: float = param(30, "m/s", "maximum desired speed", low=0)
    adaptation: float = param(0.65, "s", "time to reach the optimal velocity", low=0, strict=True)
    h_st: float = param(5, "m", "gap below which the optimal velocity is 0", low=0)
    time_delay: float = declared(TIME_DELAY)
    noise: float = declared(NOISE)
    fail_safe: FailSafe = declared(FAIL_SAFE)
    display_warnings: bool = declared(DISPLAY_WARNINGS)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        return linear_ovm_accel(
            inputs.speed, inputs.headway,
            v_max=self.v_max, adaptation=self.adaptation, h_st=self.h_st,
        )  # fmt: skip


@dataclass(eq=False)
class BandoFTLController(AccelerationController):
    """Bando optimal velocity with a follow-the-leader term (see :func:`bando_ftl_accel`).

    ``h_go`` is accepted for Flow compatibility; the tanh velocity function does not use it.
    """

    registered_name = "BandoFTL"

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)
    alpha: float = param(0.5, "1/s", "gain on the optimal-velocity error", low=0)
    beta: float = param(20, "m^2/s", "gain of the follow-the-leader term", low=0)
    h_st: float = param(2, "m", "gap scale of the tanh velocity function", low=0, strict=True)
    h_go: float = param(10, "m", "accepted for Flow, unused", low=0)
    v_max: float = param(32, "m/s", "maximum desired speed", low=0)
    want_max_accel: bool = option(False, "maximum acceleration without a leader", flag)
    time_delay: float = declared(TIME_DELAY)
    noise: float = declared(NOISE)
    fail_safe: FailSafe = declared(FAIL_SAFE)
    display_warnings: bool = declared(DISPLAY_WARNINGS)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        h, v_lead = inputs.headway, inputs.leader_speed
        if not self.want_max_accel and not inputs.has_leader.all():
            # Without a leader Flow's controller reads its getters' "none" values, a gap of
            # 1000 m and a leader speed of -1001 m/s: V = v_max and the follow-the-leader
            # term is beta * (-1001 - v) / 1000^2 (about -0.02 m/s^2 with beta = 20)
            alone = ~inputs.has_leader
            h = np.where(alone, FLOW_NO_GAP, h)
            v_lead = np.where(alone, FLOW_ERROR, v_lead)
        accel = bando_ftl_accel(
            inputs.speed, h, v_lead,
            alpha=self.alpha, beta=self.beta, h_st=self.h_st, v_max=self.v_max,
        )  # fmt: skip
        return _free_road(inputs, accel) if self.want_max_accel else accel


@dataclass(eq=False)
class GippsController(AccelerationController):
    """Gipps' model (see :func:`gipps_accel`); ``b`` and ``b_l`` are negative, as in Flow."""

    registered_name = "Gipps"

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)
    v0: float = param(30, "m/s", "desired speed", low=0, strict=True)
    acc: float = param(1.5, "m/s^2", "maximum acceleration", low=0, strict=True)
    b: float = param(-1, "m/s^2", "most severe braking", high=0, strict=True, what=_NEGATIVE)
    b_l: float = param(-1, "m/s^2", "leader's most severe braking", high=0, strict=True,
                       what=_NEGATIVE)  # fmt: skip
    s0: float = param(2, "m", "minimum gap", low=0)
    tau: float = param(1, "s", "reaction time", low=0, strict=True)
    delay: float = declared(TIME_DELAY)
    noise: float = declared(NOISE)
    fail_safe: FailSafe = declared(FAIL_SAFE)
    display_warnings: bool = declared(DISPLAY_WARNINGS)

    def __post_init__(self) -> None:
        super().__post_init__()
        self.time_delay = self.delay  # Flow's name here; the fail-safes read time_delay

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        return gipps_accel(
            inputs.speed, inputs.headway, inputs.leader_speed, inputs.dt,
            v0=self.v0, acc=self.acc, b=self.b, b_l=self.b_l, s0=self.s0, tau=self.tau,
        )  # fmt: skip


@dataclass(eq=False)
class LACController(AccelerationController):
    """Linear adaptive cruise control (Flow's ``LACController``; stateful).

    The commanded acceleration follows a first-order lag of time constant ``tau`` towards
    ``u = k_1 * e_x + k_2 * e_v``, with the spacing error ``e_x = headway - length - h * v``
    (Flow subtracts the ego's length from the bumper-to-bumper headway) and the speed error
    ``e_v = v_lead - v``: ``a <- a + dt * (u - a) / tau``. Without a leader ``u = 0`` (Flow
    has no such case: it would fail). The vehicle length is 5 m when the kernel gives none.
    """

    registered_name = "LAC"
    aliases = ("LACController",)
    stateful = True

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)
    k_1: float = param(0.3, "1/s^2", "gain on the spacing error")
    k_2: float = param(0.4, "1/s", "gain on the speed error")
    h: float = param(1, "s", "desired time gap", low=0)
    tau: float = param(0.1, "s", "lag between command and acceleration", low=0, strict=True)
    a: float = param(0, "m/s^2", "initial acceleration")
    time_delay: float = declared(TIME_DELAY)
    noise: float = declared(NOISE)
    fail_safe: FailSafe = declared(FAIL_SAFE)
    display_warnings: bool = declared(DISPLAY_WARNINGS)

    def __post_init__(self) -> None:
        super().__post_init__()
        self._state = np.zeros(0)

    def reset(self, num_vehicles: int) -> None:
        """Every vehicle's acceleration starts at ``a``."""
        self._state = np.full(num_vehicles, self.a)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        n = inputs.size
        if self._state.size != n:
            self.reset(n)
        length = inputs.length if inputs.length is not None else np.full(n, 5.0)
        v = inputs.speed
        lead = inputs.has_leader
        e_x = np.where(lead, inputs.headway - length - self.h * v, 0.0)
        e_v = np.where(lead, inputs.leader_speed - v, 0.0)
        u = self.k_1 * e_x + self.k_2 * e_v
        self._state = self._state + inputs.dt * (u - self._state) / self.tau
        return self._state.copy()
