"""The single-lane ring as SUMO moves it, as pure vectorised formulas over many rings at once.

Arrays are *car-major*: shape ``(N, B)`` for ``N`` cars on each of ``B`` rings, so the rows of
one vehicle group are one contiguous block (a group's controller gets them without a copy).

What SUMO does on flowrun's ring (SUMO 1.28, ``--step-length dt``, Euler update), reproduced
here and checked car by car against the SUMO backend in ``tests/test_fastring_sumo.py``:

- A commanded car (flowrun's ``slowDown(v + a*dt)``) gets ``v' = min(max(v + a*dt, 0), limit)``;
  with speed-mode bit 0 ("regard safe speed", Flow's ``obey_safe_speed``/``right_of_way``)
  SUMO caps it by its car-following model's follow speed: ``v' = min(v', v_safe)``.
- A car nobody commands (the RL car during the warm-up) is driven by SUMO's own IDM:
  ``v' = max(v_min, min(v_safe, v + accel*dt, max_speed, lane max))``
  (``MSCFModel::finalizeSpeed``).
- ``x' = x + v'*dt``; leaders come from the cyclic order of the cars (no passing on one lane);
  SUMO reports a collision when a gap falls below ``-NUMERICAL_EPS``.
"""

from __future__ import annotations

import math

import numpy as np

from flowrun.types import FloatArray, IntArray

#: SUMO's ``NUMERICAL_EPS`` (m, m/s): smallest gap/speed its formulas divide by, and the
#: overlap (m) beyond which it reports a collision.
NUMERICAL_EPS = 0.001

#: SUMO's default emergency deceleration of a passenger car, m/s^2 (``emergencyDecel``).
DEFAULT_EMERGENCY_DECEL = 9.0

#: SUMO's default integration step of its IDM (``stepping``), s.
IDM_STEPPING = 0.25


def idm_iterations(dt: float) -> int:
    """Sub-steps SUMO's IDM integrates one step in: ``max(1, int(dt/0.25 + 0.5))``."""
    return max(1, int(dt / IDM_STEPPING + 0.5))


def sumo_idm_follow_speed(
    v: FloatArray,
    gap: FloatArray,
    v_lead: FloatArray,
    *,
    des_speed: FloatArray | float,
    accel: FloatArray | float,
    decel: FloatArray | float,
    tau: FloatArray | float,
    min_gap: FloatArray | float,
    dt: float,
    delta: float = 4.0,
) -> FloatArray:
    """SUMO's IDM follow speed (``MSCFModel_IDM::followSpeed``/``_v``): the next speed, m/s.

    ``s = max(0, v*tau + v*(v - v_lead)/(2*sqrt(accel*decel))) + min_gap`` and
    ``v' = max(0, v + dt/k * accel*(1 - (v/v_des)^delta - (s/gap)^2))`` over ``k`` sub-steps
    (:func:`idm_iterations`), the gap shrinking by ``max(0, (v' - v_lead)*dt/k)`` after each.

    Args:
        v: ego speed, m/s.
        gap: bumper-to-bumper gap to the leader, m (SUMO's ``gap2pred + minGap``).
        v_lead: leader speed, m/s.
        des_speed: the car's maximum speed on the lane, m/s.
        accel: ``accel`` of the vehicle type, m/s^2. decel: its ``decel``, m/s^2.
        tau: its ``tau`` (time headway), s. min_gap: its ``minGap``, m.
        dt: simulation step, s.
        delta: IDM exponent (SUMO's default 4).
    """
    iterations = idm_iterations(dt)
    two_sqrt = 2.0 * np.sqrt(np.multiply(accel, decel))
    des = np.maximum(NUMERICAL_EPS, des_speed)
    speed = v
    g = gap
    for _ in range(iterations):
        s = np.maximum(0.0, speed * tau + speed * (speed - v_lead) / two_sqrt) + min_gap
        g = np.maximum(NUMERICAL_EPS, g)
        acc = accel * (1.0 - np.power(speed / des, delta) - (s * s) / (g * g))
        speed = np.maximum(0.0, speed + acc * dt / iterations)
        if iterations > 1:
            g = g - np.maximum(0.0, (speed - v_lead) * dt / iterations)
    return np.maximum(0.0, speed)


def commanded_speed(v: FloatArray, accel: FloatArray, dt: float, limit: float) -> FloatArray:
    """flowrun's command to SUMO: ``min(max(v + a*dt, 0), limit)`` (m/s)."""
    return np.minimum(np.maximum(v + accel * dt, 0.0), limit)


def sumo_driven_speed(
    v: FloatArray,
    v_safe: FloatArray,
    *,
    accel: FloatArray | float,
    decel: FloatArray | float,
    emergency_decel: FloatArray | float,
    max_speed: FloatArray | float,
    lane_max: FloatArray | float,
    dt: float,
) -> FloatArray:
    """Next speed of a car SUMO's IDM drives (no command), m/s (``finalizeSpeed``, Euler).

    ``v_min = min(max(v - dt*max(decel, min(emergency, 1.5)), 0), max(v_safe, v_emergency))``,
    ``v_max = min(v + dt*(lane_max - v)/dt, v + accel*dt, max_speed, v_safe)``, result
    ``max(v_min, v_max)``.
    """
    v_emergency = np.maximum(v - emergency_decel * dt, 0.0)
    brake = np.maximum(decel, np.minimum(emergency_decel, 1.5))
    v_min = np.minimum(np.maximum(v - brake * dt, 0.0), np.maximum(v_safe, v_emergency))
    lane = v + (lane_max - v) / dt * dt
    v_max = np.minimum(np.minimum(lane, np.minimum(v + accel * dt, max_speed)), v_safe)
    return np.maximum(v_min, v_max)


def ring_order(
    position: FloatArray, lengths: FloatArray, length: FloatArray
) -> tuple[IntArray, IntArray, FloatArray]:
    """Leader, follower and headway offset of every car of every ring (arrays ``(N, B)``).

    Cars are sorted by position on each ring; a car's leader is the next one ahead. The
    headway is then ``u[leader] - u + offset`` for unwrapped positions ``u`` (start + distance
    driven), with ``offset`` = one ring length for the car whose leader is ahead across the
    start, minus the leader's length — as flowrun's SUMO kernel computes it
    (:class:`~flowrun.kernel.following.RingFollowing`).

    Args:
        position: unwrapped positions, m, ``(N, B)``.
        lengths: car lengths, m, ``(N,)``.
        length: ring lengths, m, ``(B,)``.
    """
    n, b = position.shape
    wrapped = np.mod(position, length)
    order = np.argsort(wrapped, axis=0, kind="stable")
    ahead = np.roll(order, -1, axis=0)
    cols = np.arange(b)
    leader = np.empty((n, b), dtype=np.int64)
    leader[order, cols] = ahead
    follower = np.empty((n, b), dtype=np.int64)
    follower[ahead, cols] = order
    diff = position[leader, cols] - position
    wrap = length * np.round((np.mod(diff, length) - diff) / length)
    return leader, follower, wrap - lengths[leader]


def flat_index(rows: IntArray) -> IntArray:
    """Indices into a raveled ``(N, B)`` array of the entries ``[rows[i, j], j]``."""
    return rows * rows.shape[1] + np.arange(rows.shape[1])


def noise_term(dt: float, noise: float, z: FloatArray) -> FloatArray:
    """Flow's acceleration noise ``sqrt(dt) * N(0, noise)`` from standard normals ``z``
    (the same arithmetic as numpy's ``normal(0, noise)``: ``0 + noise*z``)."""
    return math.sqrt(dt) * (noise * z)
