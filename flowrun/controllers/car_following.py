"""Car-following controllers: the classes binding the pure formulas of
:mod:`flowrun.controllers.car_following_formulas` (re-exported here) to vehicle groups.

Conventions (see :class:`~flowrun.controllers.base.CarFollowingInputs`): ``h`` is the
bumper-to-bumper gap to the leader in m (``inf`` without a leader), speeds are in m/s.

Without a leader, Flow's CFM, BCM and OVM controllers (and Bando-FTL with
``want_max_accel=True``) command the vehicle type's maximum acceleration; the classes here do
the same, using ``inputs.max_accel`` (the vehicle type's ``accel``, filled by the kernel or
from the controller's ``car_following_params``) or, when neither is known, SUMO's default
2.6 m/s^2.

The constructors take Flow's leading ``veh_id`` (and ``car_following_params`` where Flow
has it), so ``IDMController("human_0", car_following_params=...)`` works as in Flow.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from flowrun.controllers._checks import number
from flowrun.controllers.base import (
    DEFAULT_MAX_ACCEL,
    AccelerationController,
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
from flowrun.flow_values import FLOW_ERROR, FLOW_NO_GAP
from flowrun.types import CarFollowingInputs, FloatArray


def _free_road(inputs: CarFollowingInputs, accel: FloatArray) -> FloatArray:
    """Replace the command of vehicles without a leader by their maximum acceleration."""
    max_accel = inputs.max_accel if inputs.max_accel is not None else DEFAULT_MAX_ACCEL
    return np.where(inputs.has_leader, accel, max_accel)


class IDMController(AccelerationController):
    """Intelligent Driver Model (see :func:`idm_accel`); Flow's defaults."""

    registered_name = "IDM"

    def __init__(
        self,
        veh_id: str | None = None,
        v0: float = 30,
        T: float = 1,
        a: float = 1,
        b: float = 1.5,
        delta: float = 4,
        s0: float = 2,
        time_delay: float = 0.0,
        noise: float = 0,
        fail_safe: str | Sequence[str] | None = None,
        display_warnings: bool = True,
        car_following_params: Any = None,
    ) -> None:
        super().__init__(
            noise=noise, fail_safe=fail_safe, time_delay=time_delay, veh_id=veh_id,
            car_following_params=car_following_params, display_warnings=display_warnings,
        )  # fmt: skip
        me = type(self).__name__
        self.v0 = number(me, "v0", v0, low=0, strict=True, allow_inf=True)
        self.T = number(me, "T", T, low=0)
        self.a = number(me, "a", a, low=0, strict=True)
        self.b = number(me, "b", b, low=0, strict=True)
        self.delta = number(me, "delta", delta, low=0, strict=True)
        self.s0 = number(me, "s0", s0, low=0)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        return idm_accel(
            inputs.speed, inputs.headway, inputs.leader_speed,
            v0=self.v0, T=self.T, a=self.a, b=self.b, delta=self.delta, s0=self.s0,
        )  # fmt: skip


class CFMController(AccelerationController):
    """Linear car-following model (see :func:`cfm_accel`); max accel without a leader."""

    registered_name = "CFM"

    def __init__(
        self,
        veh_id: str | None = None,
        car_following_params: Any = None,
        k_d: float = 1,
        k_v: float = 1,
        k_c: float = 1,
        d_des: float = 1,
        v_des: float = 8,
        time_delay: float = 0.0,
        noise: float = 0,
        fail_safe: str | Sequence[str] | None = None,
        display_warnings: bool = True,
    ) -> None:
        super().__init__(
            noise=noise, fail_safe=fail_safe, time_delay=time_delay, veh_id=veh_id,
            car_following_params=car_following_params, display_warnings=display_warnings,
        )  # fmt: skip
        me = type(self).__name__
        self.k_d = number(me, "k_d", k_d, low=0)
        self.k_v = number(me, "k_v", k_v, low=0)
        self.k_c = number(me, "k_c", k_c, low=0)
        self.d_des = number(me, "d_des", d_des, low=0)
        self.v_des = number(me, "v_des", v_des, low=0)

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


class OVMController(AccelerationController):
    """Optimal Velocity Model (see :func:`ovm_accel`); max accel without a leader."""

    registered_name = "OVM"

    def __init__(
        self,
        veh_id: str | None = None,
        car_following_params: Any = None,
        alpha: float = 1,
        beta: float = 1,
        h_st: float = 2,
        h_go: float = 15,
        v_max: float = 30,
        time_delay: float = 0,
        noise: float = 0,
        fail_safe: str | Sequence[str] | None = None,
        display_warnings: bool = True,
    ) -> None:
        super().__init__(
            noise=noise, fail_safe=fail_safe, time_delay=time_delay, veh_id=veh_id,
            car_following_params=car_following_params, display_warnings=display_warnings,
        )  # fmt: skip
        me = type(self).__name__
        self.alpha = number(me, "alpha", alpha, low=0)
        self.beta = number(me, "beta", beta, low=0)
        self.h_st = number(me, "h_st", h_st, low=0)
        self.h_go = number(me, "h_go", h_go, low=self.h_st, strict=True)
        self.v_max = number(me, "v_max", v_max, low=0)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        accel = ovm_accel(
            inputs.speed, inputs.headway, inputs.leader_speed,
            alpha=self.alpha, beta=self.beta, h_st=self.h_st, h_go=self.h_go, v_max=self.v_max,
        )  # fmt: skip
        return _free_road(inputs, accel)


class LinearOVM(AccelerationController):
    """Linear optimal-velocity model (see :func:`linear_ovm_accel`)."""

    registered_name = "LinearOVM"

    def __init__(
        self,
        veh_id: str | None = None,
        car_following_params: Any = None,
        v_max: float = 30,
        adaptation: float = 0.65,
        h_st: float = 5,
        time_delay: float = 0.0,
        noise: float = 0,
        fail_safe: str | Sequence[str] | None = None,
        display_warnings: bool = True,
    ) -> None:
        super().__init__(
            noise=noise, fail_safe=fail_safe, time_delay=time_delay, veh_id=veh_id,
            car_following_params=car_following_params, display_warnings=display_warnings,
        )  # fmt: skip
        me = type(self).__name__
        self.v_max = number(me, "v_max", v_max, low=0)
        self.adaptation = number(me, "adaptation", adaptation, low=0, strict=True)
        self.h_st = number(me, "h_st", h_st, low=0)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        return linear_ovm_accel(
            inputs.speed, inputs.headway,
            v_max=self.v_max, adaptation=self.adaptation, h_st=self.h_st,
        )  # fmt: skip


class BandoFTLController(AccelerationController):
    """Bando optimal velocity with a follow-the-leader term (see :func:`bando_ftl_accel`).

    ``h_go`` is accepted for Flow compatibility; the tanh velocity function does not use it.
    """

    registered_name = "BandoFTL"

    def __init__(
        self,
        veh_id: str | None = None,
        car_following_params: Any = None,
        alpha: float = 0.5,
        beta: float = 20,
        h_st: float = 2,
        h_go: float = 10,
        v_max: float = 32,
        want_max_accel: bool = False,
        time_delay: float = 0,
        noise: float = 0,
        fail_safe: str | Sequence[str] | None = None,
        display_warnings: bool = True,
    ) -> None:
        super().__init__(
            noise=noise, fail_safe=fail_safe, time_delay=time_delay, veh_id=veh_id,
            car_following_params=car_following_params, display_warnings=display_warnings,
        )  # fmt: skip
        me = type(self).__name__
        self.alpha = number(me, "alpha", alpha, low=0)
        self.beta = number(me, "beta", beta, low=0)
        self.h_st = number(me, "h_st", h_st, low=0, strict=True)
        self.h_go = number(me, "h_go", h_go, low=0)
        self.v_max = number(me, "v_max", v_max, low=0)
        if not isinstance(want_max_accel, bool):
            raise ValueError(f"{me}: want_max_accel must be true or false, got {want_max_accel!r}")
        self.want_max_accel = want_max_accel

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


class GippsController(AccelerationController):
    """Gipps' model (see :func:`gipps_accel`); ``b`` and ``b_l`` are negative, as in Flow."""

    registered_name = "Gipps"

    def __init__(
        self,
        veh_id: str | None = None,
        car_following_params: Any = None,
        v0: float = 30,
        acc: float = 1.5,
        b: float = -1,
        b_l: float = -1,
        s0: float = 2,
        tau: float = 1,
        delay: float = 0,
        noise: float = 0,
        fail_safe: str | Sequence[str] | None = None,
        display_warnings: bool = True,
    ) -> None:
        super().__init__(
            noise=noise, fail_safe=fail_safe, time_delay=delay, veh_id=veh_id,
            car_following_params=car_following_params, display_warnings=display_warnings,
        )  # fmt: skip
        me = type(self).__name__
        self.v0 = number(me, "v0", v0, low=0, strict=True)
        self.acc = number(me, "acc", acc, low=0, strict=True)
        self.b = number(me, "b", b)
        self.b_l = number(me, "b_l", b_l)
        for name, value in (("b", self.b), ("b_l", self.b_l)):
            if value >= 0:
                raise ValueError(f"{me}: {name} must be a negative deceleration, got {value:g}")
        self.s0 = number(me, "s0", s0, low=0)
        self.tau = number(me, "tau", tau, low=0, strict=True)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        return gipps_accel(
            inputs.speed, inputs.headway, inputs.leader_speed, inputs.dt,
            v0=self.v0, acc=self.acc, b=self.b, b_l=self.b_l, s0=self.s0, tau=self.tau,
        )  # fmt: skip


class LACController(AccelerationController):
    """Linear adaptive cruise control (Flow's ``LACController``; stateful).

    The commanded acceleration follows a first-order lag of time constant ``tau`` towards
    ``u = k_1 * e_x + k_2 * e_v``, with the spacing error ``e_x = headway - length - h * v``
    (Flow subtracts the ego's length from the bumper-to-bumper headway) and the speed error
    ``e_v = v_lead - v``: ``a <- a + dt * (u - a) / tau``. Without a leader ``u = 0`` (Flow
    has no such case: it would fail). The vehicle length is 5 m when the kernel gives none.

    Args:
        k_1: gain on the spacing error, 1/s^2.
        k_2: gain on the speed error, 1/s.
        h: desired time gap, s.
        tau: lag between command and acceleration, s.
        a: initial acceleration, m/s^2.
    """

    registered_name = "LAC"
    aliases = ("LACController",)
    stateful = True

    def __init__(
        self,
        veh_id: str | None = None,
        car_following_params: Any = None,
        k_1: float = 0.3,
        k_2: float = 0.4,
        h: float = 1,
        tau: float = 0.1,
        a: float = 0,
        time_delay: float = 0.0,
        noise: float = 0,
        fail_safe: str | Sequence[str] | None = None,
        display_warnings: bool = True,
    ) -> None:
        super().__init__(
            noise=noise, fail_safe=fail_safe, time_delay=time_delay, veh_id=veh_id,
            car_following_params=car_following_params, display_warnings=display_warnings,
        )  # fmt: skip
        me = type(self).__name__
        self.k_1 = number(me, "k_1", k_1)
        self.k_2 = number(me, "k_2", k_2)
        self.h = number(me, "h", h, low=0)
        self.tau = number(me, "tau", tau, low=0, strict=True)
        self.a = number(me, "a", a)
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
