"""The all-human ring on real SUMO reproduces Sugiyama's experiment and Flow's numbers.

Published reference (Flow, all-human ring, 22 IDM cars, mean speed over the last half of a
300 s run): 2.41 m/s at 230 m and 3.32 m/s at 260 m. Sugiyama et al. (2008) measured the
jam travelling backwards at about 20 km/h.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

pytestmark = pytest.mark.sumo

STEPS = 3000  # 300 s at dt = 0.1 s
CAR_LENGTH = 5.0


def idm_params(cfg: Any) -> dict[str, float]:
    """The IDM parameters of the config's (single) vehicle group, Flow's defaults filled in."""
    params = {"v0": 30.0, "T": 1.0, "a": 1.0, "b": 1.5, "delta": 4.0, "s0": 2.0}
    spec = cfg.vehicles.groups[0].acceleration_controller
    assert spec.type == "IDM"
    params.update({k: float(v) for k, v in spec.params.items() if k in params})
    return params


def uniform_flow_speed(length: float, n: int, p: dict[str, float]) -> float:
    """Equilibrium speed of ``n`` evenly spaced IDM cars on a ring (bisection, m/s).

    Every car has gap ``h = length/n - car length`` and the same speed ``v``; IDM's
    acceleration is zero when ``1 - (v/v0)^delta - ((s0 + v*T)/h)^2 = 0``, which is
    decreasing in ``v``.
    """
    h = length / n - CAR_LENGTH

    def accel(v: float) -> float:
        return 1.0 - (v / p["v0"]) ** p["delta"] - ((p["s0"] + v * p["T"]) / h) ** 2

    lo, hi = 0.0, p["v0"]
    assert accel(lo) > 0 > accel(hi)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if accel(mid) > 0 else (lo, mid)
    return 0.5 * (lo + hi)


def idm_euler(
    x0: np.ndarray, v0: np.ndarray, length: float, steps: int, dt: float, p: dict[str, float]
) -> tuple[np.ndarray, np.ndarray]:
    """Pure IDM on a ring with Euler steps: ``v' = max(v + a*dt, 0)``, ``x' = x + v'*dt``."""
    order = np.argsort(x0)
    leader = np.empty_like(order)
    leader[order] = np.roll(order, -1)
    x, v = x0.astype(float).copy(), v0.astype(float).copy()
    xs, vs = [x.copy()], [v.copy()]
    for _ in range(steps):
        h = np.mod(x[leader] - x, length) - CAR_LENGTH
        dv = v - v[leader]
        s_star = p["s0"] + np.maximum(0.0, v * p["T"] + v * dv / (2 * math.sqrt(p["a"] * p["b"])))
        a = p["a"] * (1 - (v / p["v0"]) ** p["delta"] - (s_star / h) ** 2)
        v = np.maximum(v + a * dt, 0.0)
        x = x + v * dt
        xs.append(np.mod(x, length))
        vs.append(v.copy())
    return np.array(xs), np.array(vs)


def jam_velocity(traj: Any, seconds: float = 100.0) -> float:
    """Drift (m/s) of the slowest car's ring position over the last ``seconds``, unwrapped.

    The slowest car marks the jam; its position jumps backwards from car to car as the wave
    moves, so a straight-line fit of the unwrapped position over time is the wave's speed
    (negative: against the driving direction).
    """
    n = round(seconds / traj.dt)
    speed, pos = traj.speed[-n:], traj.position[-n:]
    slowest = pos[np.arange(n), speed.argmin(axis=1)]
    unwrapped = np.unwrap(slowest * 2 * np.pi / traj.length) * traj.length / (2 * np.pi)
    return float(np.polyfit(np.arange(n) * traj.dt, unwrapped, 1)[0])


@pytest.fixture(scope="module")
def ring230(config: Any, rollout: Any) -> Any:
    return rollout(config("sugiyama"), STEPS)


@pytest.fixture(scope="module")
def ring260(config: Any, rollout: Any) -> Any:
    return rollout(config("sugiyama_260"), STEPS)


def last_half(traj: Any) -> np.ndarray:
    return traj.speed[1 + STEPS // 2 :]


# --- stop-and-go ---------------------------------------------------------------------------


def test_230m_ring_last_half_mean_speed_matches_flow(ring230: Any) -> None:
    assert last_half(ring230).mean() == pytest.approx(2.41, rel=0.05)


def test_260m_ring_last_half_mean_speed_matches_flow(ring260: Any) -> None:
    assert last_half(ring260).mean() == pytest.approx(3.32, rel=0.05)


def test_jammed_ring_is_well_below_uniform_flow_equilibrium(
    config: Any, ring230: Any, ring260: Any
) -> None:
    for name, traj, expected in (("sugiyama", ring230, 3.45), ("sugiyama_260", ring260, 4.82)):
        cfg = config(name)
        n = cfg.vehicles.num_vehicles
        v_eq = uniform_flow_speed(traj.length, n, idm_params(cfg))
        assert v_eq == pytest.approx(expected, abs=0.01), name
        assert last_half(traj).mean() < 0.8 * v_eq, name


def test_cars_come_to_a_near_stop(ring230: Any, ring260: Any) -> None:
    assert last_half(ring230).min() < 0.5
    assert last_half(ring260).min() < 0.5


def test_jam_travels_backwards_at_sugiyama_speed(ring230: Any, ring260: Any) -> None:
    # Measured here: -15.9 km/h on both rings (Sugiyama: about 20 km/h on the track).
    for traj in (ring230, ring260):
        kmh = jam_velocity(traj) * 3.6
        assert -20.0 < kmh < -12.0, kmh


def test_ring_has_no_collisions_or_teleports(ring230: Any, ring260: Any) -> None:
    for traj in (ring230, ring260):
        assert traj.collisions == 0
        assert traj.teleports == 0


def test_sumo_ring_matches_pure_idm_euler_integration(config: Any, ring230: Any) -> None:
    p = idm_params(config("sugiyama"))
    x, v = idm_euler(ring230.position[0], ring230.speed[0], ring230.length, STEPS, ring230.dt, p)
    assert np.abs(v - ring230.speed).max() < 1e-9
    dx = np.mod(x - ring230.position + ring230.length / 2, ring230.length) - ring230.length / 2
    assert np.abs(dx).max() < 1e-7


# --- seeds ---------------------------------------------------------------------------------


def test_same_seed_gives_bit_identical_states(config: Any, rollout: Any) -> None:
    a = rollout(config("sugiyama_noise", "sim.seed=3"), 600)
    b = rollout(config("sugiyama_noise", "sim.seed=3"), 600)
    np.testing.assert_array_equal(a.speed, b.speed)
    np.testing.assert_array_equal(a.position, b.position)


def test_different_seeds_with_noise_give_different_trajectories(config: Any, rollout: Any) -> None:
    a = rollout(config("sugiyama_noise", "sim.seed=3"), 100)
    b = rollout(config("sugiyama_noise", "sim.seed=4"), 100)
    np.testing.assert_array_equal(a.speed[0], b.speed[0])  # same start: all at rest
    assert np.abs(a.speed[-1] - b.speed[-1]).max() > 1e-3


# --- single car, several lanes -------------------------------------------------------------


@pytest.mark.parametrize(("v0", "limit"), [(30.0, 20.0), (10.0, 20.0)])
def test_single_car_converges_to_lower_of_v0_and_speed_limit(
    config: Any, rollout: Any, v0: float, limit: float
) -> None:
    cfg = config(
        "sugiyama",
        "vehicles[0].count=1",
        f"vehicles[0].acceleration_controller.v0={v0}",
        f"network.speed_limit={limit}",
        "network.length=2000",
    )
    traj = rollout(cfg, 1200)
    assert traj.speed[-1, 0] == pytest.approx(min(v0, limit), abs=0.05)
    assert traj.speed.max() <= min(v0, limit) + 1e-6


def test_two_lane_ring_runs_without_collisions_on_both_lanes(config: Any, rollout: Any) -> None:
    traj = rollout(config("sugiyama", "vehicles[0].count=44", "network.lanes=2"), 1500)
    assert traj.collisions == 0
    assert traj.teleports == 0
    for lanes in traj.lanes:
        assert set(np.unique(lanes)) == {0, 1}
    assert traj.speed[-1].mean() > 0.5  # still moving
