"""Flow's reward functions that take the env, with Flow's signatures (``flow.core.rewards``).

Each reads the env through Flow's API (``env.k.vehicle`` getters, ``env.k.network``,
``env.env_params.additional_params``, ``env.sim_step``) and evaluates a pure formula of
:mod:`flowrun.envs.rewards`, so the formulas stay testable with plain arrays; flowrun's own
envs call those formulas directly.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np

from flowrun.envs import rewards as formulas
from flowrun.envs.rewards import FLOAT32_EPS
from flowrun.types import FloatArray


def _speeds(env: Any, veh_ids: Sequence[str]) -> FloatArray:
    """Speeds (m/s) of ``veh_ids`` as a float array (empty for no ids)."""
    if not veh_ids:
        return np.zeros(0)
    return np.asarray(env.k.vehicle.get_speed(list(veh_ids)), dtype=np.float64).reshape(-1)


def _all_speeds(env: Any) -> FloatArray:
    """Every car's speed, m/s, in ``get_ids()`` order (the kernel's array when it has one)."""
    speed = getattr(env.k.vehicle, "speed", None)
    if isinstance(speed, np.ndarray):
        return np.array(speed, dtype=np.float64)  # a copy: callers may not write into it
    return _speeds(env, env.k.vehicle.get_ids())


def _v_top(env: Any) -> float:
    """Largest speed limit over the network's edges, m/s."""
    network = env.k.network
    return max(float(network.speed_limit(edge)) for edge in network.get_edge_list())


def desired_velocity(env: Any, fail: bool = False, edge_list: Iterable[str] | None = None) -> float:
    """1 when every car (on ``edge_list``, if given) drives ``target_velocity``, down to 0.

    ``max(|t| - |v - t|, 0) / |t|`` with Euclidean norms over the cars; 0 on ``fail``, with no
    cars, or when a speed is below -100 m/s. ``target_velocity`` (m/s) comes from
    ``env.env_params.additional_params``.
    """
    vk = env.k.vehicle
    if edge_list is None:
        speeds = _all_speeds(env)
    else:
        speeds = _speeds(env, vk.get_ids_by_edge(list(edge_list)))
    if speeds.size and speeds.min() < -100:
        return 0.0
    target = float(env.env_params.additional_params["target_velocity"])
    return formulas.desired_velocity(speeds, target, fail=fail)


def average_velocity(env: Any, fail: bool = False) -> float:
    """Mean speed of all cars, m/s; 0 on ``fail``, with no cars, or a speed below -100."""
    speeds = _all_speeds(env)
    if fail or speeds.size == 0 or speeds.min() < -100:
        return 0.0
    return float(np.mean(speeds))


def total_velocity(env: Any, fail: bool = False) -> float:
    """Sum of all cars' speeds, m/s; 0 on ``fail`` or a speed below -100."""
    speeds = _all_speeds(env)
    if fail or (speeds.size and speeds.min() < -100):
        return 0.0
    return float(np.sum(speeds))


def rl_forward_progress(env: Any, gain: float = 0.1) -> float:
    """``gain`` times the sum of the RL cars' absolute speeds (m/s)."""
    return float(np.sum(np.abs(_speeds(env, env.k.vehicle.get_rl_ids())))) * gain


def boolean_action_penalty(
    discrete_actions: Sequence[bool] | np.ndarray, gain: float = 1.0
) -> float:
    """``gain`` times the number of true actions (Flow adds it as a penalty where used)."""
    return gain * float(np.sum(discrete_actions))


def min_delay(env: Any) -> float:
    """``max((dt*n - delay) / (dt*n), 0)``: 1 when every car drives the top speed limit.

    ``delay = dt * sum((v_top - v)/v_top)``; 0 with no cars.
    """
    cost, max_cost = formulas.min_delay_terms(_all_speeds(env), _v_top(env), env.sim_step)
    return max((max_cost - cost) / (max_cost + FLOAT32_EPS), 0.0)


def min_delay_unscaled(env: Any) -> float:
    """Average delay per car, s: ``dt * sum((v_top - v)/v_top) / n``."""
    cost, _ = formulas.min_delay_terms(_all_speeds(env), _v_top(env), env.sim_step)
    return cost / (env.k.vehicle.num_vehicles + FLOAT32_EPS)


def avg_delay_specified_vehicles(env: Any, veh_ids: Sequence[str]) -> float:
    """Delay of every car against its edge's speed limit, ``dt * sum((v_lim - v)/v_lim)``,
    divided by ``len(veh_ids)`` (Flow sums over all cars on the network's edges); 0 for no ids.
    """
    network, vk = env.k.network, env.k.vehicle
    total = 0.0
    for edge in network.get_edge_list():
        ids = vk.get_ids_by_edge(edge)
        if ids:
            v_lim = float(network.speed_limit(edge))
            total += float(np.sum((v_lim - _speeds(env, ids)) / v_lim))
    if not veh_ids:
        return 0.0
    return env.sim_step * total / len(veh_ids)


def penalize_standstill(env: Any, gain: float = 1) -> float:
    """``-gain`` per car standing still (speed exactly 0)."""
    return -gain * int(np.count_nonzero(_all_speeds(env) == 0))


def penalize_near_standstill(env: Any, thresh: float = 0.3, gain: float = 1) -> float:
    """``-gain`` per car slower than ``thresh`` m/s."""
    return -gain * int(np.count_nonzero(_all_speeds(env) < thresh))


def penalize_headway_variance(
    vehicles: Any,
    vids: Sequence[str],
    normalization: float = 1,
    penalty_gain: float = 1,
    penalty_exponent: float = 1,
) -> float:
    """Minus the variance of ``penalty_gain * (headway / normalization) ** penalty_exponent``
    over ``vids`` (``vehicles`` is ``env.k.vehicle``; headways in m)."""
    headways = np.array([vehicles.get_headway(v) / normalization for v in vids], dtype=float)
    return -float(np.var(penalty_gain * np.power(headways, penalty_exponent)))


def punish_rl_lane_changes(env: Any, penalty: float = 1) -> float:
    """``-penalty`` per RL car whose last lane change (``get_last_lc``) happened this step
    (``env.timer``, or ``env.time_counter`` when the env has no timer)."""
    vk = env.k.vehicle
    now = getattr(env, "timer", getattr(env, "time_counter", None))
    return -penalty * sum(1 for v in vk.get_rl_ids() if vk.get_last_lc(v) == now)


def _energy_ids(env: Any, veh_ids: Iterable[str]) -> list[str]:
    """The ids that have a previous speed (Flow skips cars that just entered)."""
    previous = getattr(env.k.vehicle, "previous_speeds", None)
    return [v for v in veh_ids if previous is None or v in previous]


def _power(env: Any, veh_ids: Sequence[str]) -> FloatArray:
    vk = env.k.vehicle
    speeds = _speeds(env, veh_ids)
    prev = np.array([vk.get_previous_speed(v) for v in veh_ids], dtype=np.float64)
    return formulas.power_demand(speeds, prev, env.sim_step)


def energy_consumption(env: Any, gain: float = 0.001) -> float:
    """``-gain`` times the summed power demand of all cars, W (see
    :func:`flowrun.envs.rewards.power_demand`)."""
    ids = _energy_ids(env, env.k.vehicle.get_ids())
    return -gain * float(np.sum(_power(env, ids))) if ids else 0.0


def vehicle_energy_consumption(env: Any, veh_id: str, gain: float = 0.001) -> float:
    """``-gain`` times one car's power demand, W (0 for a car without a previous speed)."""
    ids = _energy_ids(env, [veh_id])
    return -gain * float(_power(env, ids)[0]) if ids else 0.0


#: Flow's name of :func:`vehicle_energy_consumption` (``flow.core.rewards``)
veh_energy_consumption = vehicle_energy_consumption


def _mean_speed_per_rate(
    env: Any, veh_ids: Any, rate: Callable[[str], float], min_speed: float
) -> float:
    """Mean over cars with ``rate(car) > 0`` and speed >= ``min_speed`` of ``speed / rate``
    (0 when no car counts); ``veh_ids`` one id, a list, or ``None`` for every car."""
    if veh_ids is None:
        veh_ids = env.k.vehicle.get_ids()
    elif not isinstance(veh_ids, list):
        veh_ids = [veh_ids]
    total, counter = 0.0, 0
    for veh_id in veh_ids:
        speed = float(env.k.vehicle.get_speed(veh_id))
        per_s = rate(veh_id)
        if per_s > 0 and speed >= min_speed:
            counter += 1
            total += speed / per_s
    return total / counter if counter else 0.0


def miles_per_megajoule(env: Any, veh_ids: Any = None, gain: float = 0.001) -> float:
    """Mean of ``speed / power`` over cars with power > 0 and speed >= 0.1 m/s, in miles per
    megajoule (1 mile = 1609 m), times ``gain``."""
    power = lambda v: -vehicle_energy_consumption(env, v, gain=1.0)  # noqa: E731
    return _mean_speed_per_rate(env, veh_ids, power, 0.1) / 1609.0 * 1e6 * gain


def miles_per_gallon(env: Any, veh_ids: Any = None, gain: float = 0.001) -> float:
    """Mean of ``speed / fuel`` over cars burning fuel (gallons/s > 0, speed >= 0), in miles
    per gallon (1 mile = 1609 m), times ``gain``; 0 when no car burns fuel."""
    fuel = lambda v: float(env.k.vehicle.get_fuel_consumption(v))  # noqa: E731
    return _mean_speed_per_rate(env, veh_ids, fuel, 0.0) / 1609.0 * gain


def punish_small_rl_headways(
    env: Any, headway_threshold: float, penalty_gain: float = 1, penalty_exponent: float = 1
) -> float:
    """Minus the sum, over RL cars closer than ``headway_threshold`` (m) to their leader, of
    ``((threshold - headway) / threshold) ** penalty_exponent * penalty_gain`` (Flow)."""
    vk = env.k.vehicle
    total = 0.0
    for veh_id in vk.get_rl_ids():
        headway = float(vk.get_headway(veh_id))
        if headway < headway_threshold:
            total += ((headway_threshold - headway) / headway_threshold) ** penalty_exponent
    return -abs(total * penalty_gain)


def reward_rl_opening_headways(
    env: Any, reward_gain: float = 0.1, reward_exponent: float = 1
) -> float:
    """``reward_gain`` times the sum of ``headway ** reward_exponent`` of the cars following
    RL cars (m; cars without a follower, or with a negative headway, count 0) (Flow)."""
    vk = env.k.vehicle
    total = 0.0
    for rl_id in vk.get_rl_ids():
        follower = vk.get_follower(rl_id)
        if not follower:
            continue
        headway = float(vk.get_headway(follower))
        if headway >= 0 and np.isfinite(headway):
            total += headway**reward_exponent
    return total * reward_gain


def punish_queues_in_lane(
    env: Any, edge: str, lane: int, penalty_gain: float = 1, penalty_exponent: float = 1
) -> float:
    """Minus ``penalty_gain`` times (number of cars on lane ``lane`` of ``edge``) to the
    ``penalty_exponent`` (Flow)."""
    vk = env.k.vehicle
    count = sum(1 for v in vk.get_ids_by_edge(edge) if vk.get_lane(v) == lane)
    return -1.0 * (count**penalty_exponent) * penalty_gain


#: Flow's ``flow.core.rewards`` names (re-exported there by :mod:`flowrun.core.rewards`)
__all__ = [
    "average_velocity",
    "avg_delay_specified_vehicles",
    "boolean_action_penalty",
    "desired_velocity",
    "energy_consumption",
    "miles_per_gallon",
    "miles_per_megajoule",
    "min_delay",
    "min_delay_unscaled",
    "penalize_headway_variance",
    "penalize_near_standstill",
    "penalize_standstill",
    "punish_queues_in_lane",
    "punish_rl_lane_changes",
    "punish_small_rl_headways",
    "reward_rl_opening_headways",
    "rl_forward_progress",
    "total_velocity",
    "veh_energy_consumption",
    "vehicle_energy_consumption",
]
