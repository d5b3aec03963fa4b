"""Reward formulas as pure functions of arrays (Flow's ``flow.core.rewards``)."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
FLOAT32_EPS = float(np.finfo(np.float32).eps)


def desired_velocity(speeds: FloatArray, target_velocity: float, fail: bool = False) -> float:
    """Flow's ``desired_velocity``: 1 when every car drives ``target_velocity``, 0 at worst.

    ``max(|t| - |v - t|, 0) / |t|`` with ``|.|`` the Euclidean norm over all vehicles and
    ``t`` the target vector; 0 after a collision or with no vehicles.
    """
    n = speeds.size
    if fail or n == 0:
        return 0.0
    max_cost = abs(target_velocity) * math.sqrt(n)
    diff = speeds - target_velocity
    cost = math.sqrt(float(diff.dot(diff)))
    return max(max_cost - cost, 0.0) / (max_cost + FLOAT32_EPS)


def wave_attenuation_terms(
    speeds: FloatArray, rl_actions: FloatArray | None, fail: bool = False
) -> dict[str, float]:
    """Flow's ring reward, by term: ``4 * mean(v) / 20`` minus ``4 * mean(|a_rl|)``.

    Returns:
        ``{"speed": ..., "accel_penalty": ...}``; both 0 after a collision.
    """
    if fail or speeds.size == 0 or speeds.min() < -100:
        return {"speed": 0.0, "accel_penalty": 0.0}
    speed_term = 4.0 * (float(speeds.sum()) / speeds.size) / 20.0
    penalty = 0.0
    if rl_actions is not None and np.size(rl_actions):
        actions = np.abs(np.asarray(rl_actions, dtype=np.float64))
        mean_abs = float(actions.sum()) / actions.size
        penalty = -4.0 * mean_abs if mean_abs > 0 else 0.0
    return {"speed": speed_term, "accel_penalty": penalty}
