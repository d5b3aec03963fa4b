"""Car-following formulas: pure functions of arrays, one entry per vehicle, returning
accelerations in m/s^2 (Gipps: the next speed, m/s).

Conventions (see :class:`~flowrun.controllers.base.CarFollowingInputs`): ``h`` is the
bumper-to-bumper gap to the leader in m (``inf`` without a leader), speeds are in m/s. The
controller classes that bind them to a vehicle group are in
:mod:`flowrun.controllers.car_following`.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from flowrun.types import FloatArray

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
    # (a product with a factor of exactly 1 is skipped: x * 1.0 is x, bit for bit)
    headway_term = v if T == 1.0 else v * T
    v0_, two_sqrt_ab, delta_, s0_ = _idm_constants(v0, a, b, delta, s0)
    s_star = s0_ + np.maximum(ZERO, headway_term + v * (v - v_lead) / two_sqrt_ab)
    # Without a leader h = inf, so s*/h = 0 and the interaction term vanishes (Flow: s* = 0).
    interaction = np.square(s_star / np.maximum(h, _MIN_GAP))
    accel = ONE - (v / v0_) ** delta_ - interaction
    return accel if a == 1.0 else a * accel


#: 0, 1 and MIN_GAP as 0-d float64 arrays: a ufunc takes them as they are, while it converts
#: a Python float at every call (0.40 against 0.25 µs for an operation on 13 cars); the ring
#: tasks (:mod:`flowrun.envs.ring.tasks`) use ZERO and ONE too
ZERO, ONE, _MIN_GAP = np.array(0.0), np.array(1.0), np.array(MIN_GAP)


@functools.lru_cache(maxsize=64)
def _idm_constants(
    v0: float, a: float, b: float, delta: float, s0: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """IDM's ``v0``, ``2 * sqrt(a * b)``, ``delta`` and ``s0`` as 0-d float64 arrays (the
    same values as the floats; see :data:`ZERO`)."""
    return (np.array(float(v0)), np.array(2.0 * math.sqrt(a * b)), np.array(float(delta)),
            np.array(float(s0)))  # fmt: skip


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
