"""Reward formulas as pure functions of arrays (Flow's ``flow.core.rewards``)."""

from __future__ import annotations

import functools
import math

import numpy as np
import numpy.typing as npt

from flowrun.types import FloatArray

FLOAT32_EPS = float(np.finfo(np.float32).eps)


def desired_velocity(speeds: FloatArray, target_velocity: float, fail: bool = False) -> float:
    """Flow's ``desired_velocity``: 1 when every car drives ``target_velocity``, 0 at worst.

    ``max(|t| - |v - t|, 0) / |t|`` with ``|.|`` the Euclidean norm over all vehicles and
    ``t`` the target vector; 0 after a collision or with no vehicles.
    """
    n = speeds.size
    if fail or n == 0:
        return 0.0
    # both norms as Flow takes them (numpy's norm of a vector is sqrt(x . x)), the target as
    # a vector: from rest the cost equals the maximum exactly
    max_cost = _target_norm(n, float(target_velocity))
    diff = speeds - target_velocity
    cost = math.sqrt(float(diff.dot(diff)))
    return max(max_cost - cost, 0.0) / (max_cost + FLOAT32_EPS)


@functools.lru_cache(maxsize=64)
def _target_norm(n: int, target_velocity: float) -> float:
    """The norm of ``n`` cars all at ``target_velocity`` (m/s), as numpy computes it."""
    target = np.full(n, target_velocity)
    return math.sqrt(float(target.dot(target)))


def wave_attenuation_terms(
    speeds: FloatArray, rl_actions: FloatArray | None, fail: bool = False
) -> dict[str, float]:
    """Flow's ring reward, by term, of one ring: ``4 * mean(v) / 20`` minus ``4 * mean(|a_rl|)``
    (:func:`wave_attenuation_rewards`' terms for a batch of one).

    Returns:
        ``{"speed": ..., "accel_penalty": ...}``; both 0 after a collision.
    """
    if fail or speeds.size == 0:
        return {"speed": 0.0, "accel_penalty": 0.0}
    actions = np.zeros((0, 1)) if rl_actions is None else np.asarray(rl_actions, np.float64)
    speed, penalty, bad = _wave_terms(speeds.reshape(-1, 1), actions.reshape(-1, 1))
    if bad[0]:
        return {"speed": 0.0, "accel_penalty": 0.0}
    accel_penalty = 0.0 if penalty is None else float(penalty[0])
    return {"speed": float(speed[0]), "accel_penalty": accel_penalty}


def min_delay_terms(speeds: FloatArray, v_top: float, dt: float) -> tuple[float, float]:
    """Flow's delay cost and its maximum: ``dt * sum((v_top - v) / v_top)`` and ``dt * n``.

    Speeds below ``-1e-6`` m/s (Flow's marker of a car not in the network) are left out.

    Args:
        speeds: vehicle speeds, m/s.
        v_top: largest speed limit of the network, m/s.
        dt: simulation step, s.

    Returns:
        ``(cost, max_cost)``, both in s.
    """
    vel = speeds[speeds >= -1e-6]
    return dt * float(np.sum((v_top - vel) / v_top)), dt * vel.size


#: Vehicle constants of Flow's ``energy_consumption``: mass (kg), gravity (m/s^2), rolling
#: resistance and drag coefficients, air density (kg/m^3), frontal area (m^2).
MASS, GRAVITY, C_ROLL, C_DRAG, AIR_DENSITY, FRONT_AREA = 1200.0, 9.81, 0.005, 0.3, 1.225, 2.6


def power_demand(speeds: FloatArray, previous_speeds: FloatArray, dt: float) -> FloatArray:
    """Flow's lower bound of each vehicle's power demand, W.

    ``M*v*|v - v_prev|/dt + M*g*C_r*v + 0.5*rho*A*C_a*v^3`` (speeds in m/s, ``dt`` in s).
    """
    accel = np.abs(speeds - previous_speeds) / dt
    return (
        MASS * speeds * accel
        + MASS * GRAVITY * C_ROLL * speeds
        + 0.5 * AIR_DENSITY * FRONT_AREA * C_DRAG * speeds**3
    )


def _wave_terms(
    speeds: FloatArray, rl_actions: FloatArray
) -> tuple[FloatArray, FloatArray | None, npt.NDArray[np.bool_]]:
    """The speed term, the acceleration penalty (``None`` without RL cars) and whether a ring's
    speeds are out of range, per ring (speeds ``(N, B)``, actions ``(num_rl, B)``)."""
    n = speeds.shape[0]
    speed_term = 4.0 * (speeds.sum(axis=0) / n) / 20.0
    penalty = None
    if rl_actions.shape[0]:
        mean_abs = np.abs(rl_actions).sum(axis=0) / rl_actions.shape[0]
        penalty = np.where(mean_abs > 0, -4.0 * mean_abs, 0.0)
    return speed_term, penalty, speeds.min(axis=0) < -100


def wave_attenuation_rewards(
    speeds: FloatArray, rl_actions: FloatArray, fail: npt.NDArray[np.bool_]
) -> FloatArray:
    """Flow's ring reward, ``4 * mean(v) / 20 - 4 * mean(|a|)``, of many rings at once (the
    numpy backend; :func:`wave_attenuation_terms` gives one ring's terms).

    Args:
        speeds: speeds, m/s, shape ``(N, B)``: ``N`` cars on each of ``B`` rings.
        rl_actions: the RL cars' (clipped) accelerations, m/s^2, shape ``(num_rl, B)``.
        fail: whether each ring had a collision, ``(B,)``.

    Returns:
        the reward per ring, 0 where ``fail``.
    """
    speed_term, penalty, bad = _wave_terms(speeds, rl_actions)
    reward = speed_term if penalty is None else speed_term + penalty
    return np.where(fail | bad, 0.0, reward)


def desired_velocities(
    speeds: FloatArray, target_velocity: float, fail: npt.NDArray[np.bool_]
) -> FloatArray:
    """:func:`desired_velocity` of many rings at once: speeds ``(N, B)`` -> ``(B,)``."""
    n = speeds.shape[0]
    max_cost = _target_norm(n, float(target_velocity))
    diff = speeds - target_velocity
    cost = np.sqrt(np.einsum("ij,ij->j", diff, diff))
    reward = np.maximum(max_cost - cost, 0.0) / (max_cost + FLOAT32_EPS)
    return np.where(fail | (n == 0), 0.0, reward)
