"""Car-following models: pure formulas (``*_accel``) and the controller classes binding them.

Every formula takes arrays with one entry per vehicle and returns accelerations in m/s^2.
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

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from flowrun.controllers._checks import number
from flowrun.controllers.base import (
    DEFAULT_MAX_ACCEL,
    AccelerationController,
    CarFollowingInputs,
    FloatArray,
)

#: Smallest gap (m) a formula divides by: Flow's guard against ``h == 0``.
MIN_GAP = 1e-3

#: Slope of the linear optimal-velocity function, 1/s (average from Nakayama et al.).
LINEAR_OVM_SLOPE = 1.689


def idm_accel(
    v: FloatArray,
    h: FloatArray,
    v_lead: FloatArray,
    *,
    v0: float,
    T: float,
    a: float,
    b: float,
    delta: float,
    s0: float,
) -> FloatArray:
    """Intelligent Driver Model (Treiber, Hennecke & Helbing 2000).

    ``a_cmd = a * (1 - (v/v0)^delta - (s*/h)^2)`` with the desired gap
    ``s* = s0 + max(0, v*T + v*(v - v_lead) / (2*sqrt(a*b)))``.

    Args:
        v: ego speed, m/s.
        h: gap to the leader, m; ``inf`` drops the interaction term; ``h <= 1e-3`` is
            treated as ``1e-3`` (strong but finite braking).
        v_lead: leader speed, m/s.
        v0: desired speed, m/s. T: time headway, s. a: maximum acceleration, m/s^2.
        b: comfortable deceleration, m/s^2. delta: acceleration exponent. s0: jam gap, m.

    Returns:
        accelerations, m/s^2.
    """
    s_star = s0 + np.maximum(0.0, v * T + v * (v - v_lead) / (2.0 * math.sqrt(a * b)))
    # Without a leader h = inf, so s*/h = 0 and the interaction term vanishes (Flow: s* = 0).
    interaction = np.square(s_star / np.maximum(h, MIN_GAP))
    return a * (1.0 - (v / v0) ** delta - interaction)


def cosine_optimal_velocity(h: FloatArray, *, h_st: float, h_go: float, v_max: float) -> FloatArray:
    """OVM's optimal velocity (m/s): 0 below ``h_st``, ``v_max`` above ``h_go``, and
    ``v_max/2 * (1 - cos(pi*(h - h_st)/(h_go - h_st)))`` in between (gaps in m)."""
    ramp = v_max / 2.0 * (1.0 - np.cos(np.pi * (np.clip(h, h_st, h_go) - h_st) / (h_go - h_st)))
    return np.where(h <= h_st, 0.0, np.where(h < h_go, ramp, v_max))


def ovm_accel(
    v: FloatArray,
    h: FloatArray,
    v_lead: FloatArray,
    *,
    alpha: float,
    beta: float,
    h_st: float,
    h_go: float,
    v_max: float,
) -> FloatArray:
    """Optimal Velocity Model (Bando et al. 1995) with a follow-the-leader term.

    ``a_cmd = alpha*(V(h) - v) + beta*(v_lead - v)``, ``V`` from
    :func:`cosine_optimal_velocity`. alpha, beta in 1/s; gaps in m; speeds in m/s.
    """
    v_h = cosine_optimal_velocity(h, h_st=h_st, h_go=h_go, v_max=v_max)
    return alpha * (v_h - v) + beta * (v_lead - v)


def linear_ovm_accel(
    v: FloatArray, h: FloatArray, *, v_max: float, adaptation: float, h_st: float
) -> FloatArray:
    """Linear OVM: ``a_cmd = (V(h) - v) / adaptation`` (adaptation time in s).

    ``V(h) = 0`` for ``h < h_st``, ``1.689*(h - h_st)`` up to ``v_max``, then ``v_max`` (m/s).
    """
    v_h = np.clip(LINEAR_OVM_SLOPE * (h - h_st), 0.0, v_max)
    return (v_h - v) / adaptation


def cfm_accel(
    v: FloatArray,
    h: FloatArray,
    v_lead: FloatArray,
    *,
    k_d: float,
    k_v: float,
    k_c: float,
    d_des: float,
    v_des: float,
) -> FloatArray:
    """Linear car-following model: ``k_d*(h - d_des) + k_v*(v_lead - v) + k_c*(v_des - v)``.

    Gains: k_d in 1/s^2, k_v and k_c in 1/s; ``d_des`` in m, ``v_des`` in m/s.
    """
    return k_d * (h - d_des) + k_v * (v_lead - v) + k_c * (v_des - v)


def bcm_accel(
    v: FloatArray,
    h: FloatArray,
    v_lead: FloatArray,
    h_follow: FloatArray,
    v_follow: FloatArray,
    *,
    k_d: float,
    k_v: float,
    k_c: float,
    v_des: float,
) -> FloatArray:
    """Bilateral control model (Horn 2013): looks ahead and behind.

    ``a_cmd = k_d*(h - h_follow) + k_v*((v_lead - v) - (v - v_follow)) + k_c*(v_des - v)``,
    with ``h_follow`` the follower's gap to the ego (m). A missing neighbour (``inf`` gap)
    drops the spacing term; pass the ego speed as its speed to drop its velocity term.
    """
    both = np.isfinite(h) & np.isfinite(h_follow)
    spacing = np.where(both, h - np.where(both, h_follow, 0.0), 0.0)
    return k_d * spacing + k_v * ((v_lead - v) - (v - v_follow)) + k_c * (v_des - v)


def bando_ftl_accel(
    v: FloatArray,
    h: FloatArray,
    v_lead: FloatArray,
    *,
    alpha: float,
    beta: float,
    h_st: float,
    v_max: float,
) -> FloatArray:
    """Bando optimal velocity plus follow-the-leader term.

    ``V(h) = v_max * (tanh(h/h_st - 2) + tanh(2)) / (1 + tanh(2))`` (m/s) and
    ``a_cmd = alpha*(V(h) - v) + beta*(v_lead - v)/h^2``; alpha in 1/s, beta in m^2/s,
    gaps in m (at least 1e-3). ``h = inf`` gives ``alpha*(v_max - v)``.
    """
    gap = np.maximum(h, MIN_GAP)
    v_h = v_max * (np.tanh(gap / h_st - 2.0) + math.tanh(2.0)) / (1.0 + math.tanh(2.0))
    ftl = np.where(np.isfinite(h), (v_lead - v) / gap**2, 0.0)
    return alpha * (v_h - v) + beta * ftl


def gipps_next_speed(
    v: FloatArray,
    h: FloatArray,
    v_lead: FloatArray,
    *,
    v0: float,
    acc: float,
    b: float,
    b_l: float,
    s0: float,
    tau: float,
) -> FloatArray:
    """Gipps (1981) speed after one reaction time ``tau`` (s), m/s.

    ``v_acc = v + 2.5*acc*tau*(1 - v/v0)*sqrt(0.025 + v/v0)``,
    ``v_safe = tau*b + sqrt(tau^2*b^2 - b*(2*(h - s0) - tau*v - v_lead^2/b_l))`` and the
    result ``min(v_acc, v_safe, v0)``. ``b`` and ``b_l`` are decelerations given as negative
    numbers (m/s^2), as in Flow. A negative square-root argument (gap already below ``s0``)
    is taken as 0, i.e. the strongest braking the model knows.
    """
    ratio = v / v0
    v_acc = v + 2.5 * acc * tau * (1.0 - ratio) * np.sqrt(np.maximum(0.025 + ratio, 0.0))
    radicand = tau**2 * b**2 - b * (2.0 * (h - s0) - tau * v - v_lead**2 / b_l)
    v_safe = tau * b + np.sqrt(np.maximum(radicand, 0.0))
    return np.minimum(np.minimum(v_acc, v_safe), v0)


def gipps_accel(
    v: FloatArray,
    h: FloatArray,
    v_lead: FloatArray,
    dt: float,
    *,
    v0: float,
    acc: float,
    b: float,
    b_l: float,
    s0: float,
    tau: float,
) -> FloatArray:
    """Acceleration (m/s^2) reaching Gipps' next speed in one step: ``(v_next - v)/dt``."""
    v_next = gipps_next_speed(v, h, v_lead, v0=v0, acc=acc, b=b, b_l=b_l, s0=s0, tau=tau)
    return (v_next - v) / dt


#: Flow's getter values without a leader: ``get_headway`` (m) and ``get_speed(None)`` (m/s)
FLOW_NO_LEADER_GAP, FLOW_NO_LEADER_SPEED = 1000.0, -1001.0


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
            h = np.where(alone, FLOW_NO_LEADER_GAP, h)
            v_lead = np.where(alone, FLOW_NO_LEADER_SPEED, v_lead)
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
