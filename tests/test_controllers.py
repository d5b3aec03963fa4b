"""Controller formulas and classes, checked against hand-computed values (no SUMO)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from flowrun.controllers import (
    BandoFTLController,
    BCMController,
    CFMController,
    FollowerStopper,
    GippsController,
    IDMController,
    LinearOVM,
    OVMController,
    PISaturation,
    RLController,
    SimCarFollowingController,
    idm_accel,
    make_inputs,
)
from flowrun.controllers.base import AccelerationController, CarFollowingInputs

INF = math.inf


def accel(ctrl: AccelerationController, inputs: CarFollowingInputs, seed: int = 0) -> np.ndarray:
    return ctrl.get_accel(inputs, np.random.default_rng(seed))


# --- IDM ---------------------------------------------------------------------------------


def test_idm_matches_hand_computed_value() -> None:
    # v=10, h=20, v_lead=8, defaults (v0=30, T=1, a=1, b=1.5, delta=4, s0=2):
    # s* = 2 + 10*1 + 10*(10-8)/(2*sqrt(1.5)) = 12 + 8.1649658 = 20.1649658
    # a  = 1 - (10/30)^4 - (20.1649658/20)^2 = 1 - 0.0123457 - 1.0165646 = -0.0289103
    out = accel(IDMController(), make_inputs([10.0], [20.0], [8.0]))
    assert out == pytest.approx([-0.028910294235648393], rel=1e-12)


def test_idm_without_leader_is_free_road_acceleration() -> None:
    # h = inf: a = 1 - (15/30)^4 = 0.9375
    out = accel(IDMController(), make_inputs([15.0], [INF]))
    assert out == pytest.approx([0.9375])


def test_idm_zero_or_negative_headway_brakes_hard_but_finitely() -> None:
    out = accel(IDMController(), make_inputs([5.0, 5.0, 0.0], [0.0, -3.0, 0.0], [5.0, 5.0, 0.0]))
    assert np.all(np.isfinite(out))
    # s* = 2 + 5 = 7, h clamped to 1e-3: a = 1 - (1/6)^4 - (7/1e-3)^2 ≈ -4.9e7
    assert out[0] == pytest.approx(1 - (5 / 30) ** 4 - (7 / 1e-3) ** 2)
    assert out[1] == out[0]
    assert out[2] < -1e6


def test_idm_is_vectorised_and_matches_scalar_calls() -> None:
    rng = np.random.default_rng(1)
    v = rng.uniform(0, 25, 50)
    h = rng.uniform(1, 60, 50)
    vl = rng.uniform(0, 25, 50)
    vec = idm_accel(v, h, vl, v0=30, T=1, a=1, b=1.5, delta=4, s0=2)
    assert vec.shape == (50,)
    one = [
        idm_accel(v[i : i + 1], h[i : i + 1], vl[i : i + 1], v0=30, T=1, a=1, b=1.5, delta=4, s0=2)
        for i in range(50)
    ]
    assert np.allclose(vec, np.concatenate(one), rtol=0, atol=0)


def _idm_uniform_speed(length: float, cars: int, car_length: float = 5.0) -> tuple[float, float]:
    """Bisection for v with 1 - (v/30)^4 - ((2 + v*1)/h)^2 = 0 (IDM defaults, uniform flow)."""
    h = length / cars - car_length

    def f(v: float) -> float:
        return 1 - (v / 30) ** 4 - ((2 + v) / h) ** 2

    lo, hi = 0.0, 30.0
    assert f(lo) > 0 > f(hi)
    for _ in range(200):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if f(mid) > 0 else (lo, mid)
    return (lo + hi) / 2, h


@pytest.mark.parametrize(("length", "expected"), [(230.0, 3.45), (260.0, 4.82)])
def test_idm_uniform_flow_on_ring_has_zero_acceleration(length: float, expected: float) -> None:
    v_eq, h = _idm_uniform_speed(length, 22)
    assert v_eq == pytest.approx(expected, abs=0.005)
    if length == 230.0:
        assert h == pytest.approx(5.4545, abs=1e-4)
    speeds = np.full(22, v_eq)
    out = accel(IDMController(), make_inputs(speeds, np.full(22, h), speeds))
    assert out.shape == (22,)
    assert np.max(np.abs(out)) < 1e-9
    # a bit slower than v_eq accelerates, a bit faster brakes
    slow = accel(IDMController(), make_inputs([v_eq - 0.1], [h], [v_eq - 0.1]))
    fast = accel(IDMController(), make_inputs([v_eq + 0.1], [h], [v_eq + 0.1]))
    assert slow[0] > 0 > fast[0]


# --- other car-following models ------------------------------------------------------------


def test_ovm_hand_values_and_no_leader() -> None:
    # defaults alpha=1, beta=1, h_st=2, h_go=15, v_max=30; v=5, v_lead=6
    # h=8.5: V = 15*(1 - cos(pi*6.5/13)) = 15 -> a = (15-5) + (6-5) = 11
    # h=1 (<= h_st): V = 0 -> a = -5 + 1 = -4;  h=20 (>= h_go): V = 30 -> a = 25 + 1 = 26
    # no leader: Flow's max_accel (2.6 by default, or the one supplied)
    inp = make_inputs([5.0, 5.0, 5.0, 5.0], [8.5, 1.0, 20.0, INF], [6.0, 6.0, 6.0, 6.0])
    assert accel(OVMController(), inp) == pytest.approx([11.0, -4.0, 26.0, 2.6])
    inp = make_inputs([5.0], [INF], max_accel=1.0)
    assert accel(OVMController(), inp) == pytest.approx([1.0])


def test_linear_ovm_hand_values() -> None:
    # defaults v_max=30, adaptation=0.65, h_st=5; v = 5
    # h=10: V = 1.689*5 = 8.445 -> (8.445-5)/0.65 = 5.3
    # h=4: V = 0 -> -5/0.65 = -7.6923;  h=50: V = min(1.689*45, 30) = 30 -> 25/0.65 = 38.4615
    out = accel(LinearOVM(), make_inputs([5.0, 5.0, 5.0], [10.0, 4.0, 50.0]))
    assert out == pytest.approx([5.3, -5 / 0.65, 25 / 0.65])


def test_bcm_uses_follower_and_handles_missing_neighbours() -> None:
    # k_d=k_v=k_c=1, v_des=8; v=5, h=10, v_lead=6, follower gap 8 at 4 m/s:
    # 1*(10-8) + 1*((6-5) - (5-4)) + 1*(8-5) = 2 + 0 + 3 = 5
    # no follower: spacing term dropped, (v - v_follow) = 0: 0 + 1 + 3 = 4
    # no leader: max_accel 2.6
    inp = make_inputs(
        [5.0, 5.0, 5.0],
        [10.0, 10.0, INF],
        [6.0, 6.0, 6.0],
        follower_headway=[8.0, INF, 8.0],
        follower_speed=[4.0, 4.0, 4.0],
    )
    assert accel(BCMController(), inp) == pytest.approx([5.0, 4.0, 2.6])


def test_cfm_hand_value() -> None:
    # (10 - 1) + (6 - 5) + (8 - 5) = 13
    assert accel(CFMController(), make_inputs([5.0], [10.0], [6.0])) == pytest.approx([13.0])


def test_bando_ftl_hand_value() -> None:
    # alpha=.5, beta=20, h_st=2, v_max=32; v=5, h=4, v_lead=6:
    # V = 32*(tanh(4/2-2) + tanh 2)/(1 + tanh 2) = 32*0.9640276/1.9640276 = 15.7069498
    # a = 0.5*(15.7069498 - 5) + 20*(6-5)/4^2 = 5.3534749 + 1.25 = 6.6034749
    out = accel(BandoFTLController(), make_inputs([5.0], [4.0], [6.0]))
    assert out == pytest.approx([6.603474888890126])


def test_bando_ftl_no_leader_with_and_without_max_accel() -> None:
    inp = make_inputs([5.0], [INF])
    # no leader: Flow's controller reads a gap of 1000 m and a leader speed of -1001 m/s:
    # V = v_max -> 0.5*(32 - 5) + 20*(-1001 - 5)/1000^2 = 13.5 - 0.02012; want_max_accel -> 2.6
    assert accel(BandoFTLController(), inp) == pytest.approx([13.47988], abs=1e-12)
    assert accel(BandoFTLController(want_max_accel=True), inp) == pytest.approx([2.6])


def test_gipps_hand_value() -> None:
    # v=10, h=20, v_lead=8, dt=0.1, defaults (v0=30, acc=1.5, b=b_l=-1, s0=2, tau=1):
    # v_acc  = 10 + 2.5*1.5*(1 - 1/3)*sqrt(0.025 + 1/3) = 11.4965237
    # v_safe = -1 + sqrt(1 + (2*18 - 10 + 64)) = -1 + sqrt(91) = 8.5393920
    # a = (8.5393920 - 10)/0.1 = -14.6060799
    out = accel(GippsController(), make_inputs([10.0], [20.0], [8.0], dt=0.1))
    assert out == pytest.approx([-14.606079858305439])


def test_gipps_free_road_and_below_jam_gap() -> None:
    # no leader, v=0: v_acc = 2.5*1.5*sqrt(0.025) = 0.5929 -> a = 5.929 (dt = 0.1)
    out = accel(GippsController(), make_inputs([0.0, 10.0], [INF, 0.5], [0.0, 0.0], dt=0.1))
    assert out[0] == pytest.approx(2.5 * 1.5 * math.sqrt(0.025) / 0.1)
    # h < s0 with a fast car: square-root argument < 0 -> v_next = tau*b = -1 -> a = -110
    assert out[1] == pytest.approx(-110.0)


def test_follower_stopper_regions() -> None:
    # v=10, v_lead=8, v_des=15: dv- = -2; dx1 = 4.5 + 4/3 = 5.8333, dx2 = 5.25 + 2 = 7.25,
    # dx3 = 6 + 4 = 10; u = 8.  dt = 0.1
    # h=5   -> v_cmd 0                                   -> a = -100
    # h=6.5 -> 8*(6.5-5.8333)/(7.25-5.8333) = 3.7647059   -> a = -62.3529
    # h=8.625 -> 8 + (15-8)*(1.375/2.75) = 11.5           -> a = 15
    # h=12  -> 15 -> a = 50;  no leader -> 15 -> a = 50
    inp = make_inputs([10.0] * 5, [5.0, 6.5, 8.625, 12.0, INF], [8.0] * 5, dt=0.1)
    out = accel(FollowerStopper(), inp)
    assert out == pytest.approx([-100.0, -62.35294117647058, 15.0, 50.0, 50.0])


def test_follower_stopper_is_capped_by_vehicle_limits_when_given() -> None:
    inp = make_inputs([10.0, 10.0], [5.0, 12.0], [8.0, 8.0], max_accel=1.0, max_decel=3.0)
    assert accel(FollowerStopper(), inp) == pytest.approx([-3.0, 1.0])


def test_pi_saturation_two_steps_and_reset() -> None:
    # step 1: v=10, v_lead=10, h=20: U = 10; v_target = 10 + 1*(13/23) = 10.5652174
    #   dx_s = 4; alpha = clip(16/2) = 1; beta = 0.5; v_cmd = 0.5*10.5652174 + 0.5*0 = 5.2826
    #   a = (5.2826087 - 10)/0.1 = -47.173913
    # step 2: v=12, v_lead=10, h=5: U = 11; v_target = 11; dx_s = 4; alpha = 0.5; beta = 0.75
    #   v_cmd = 0.75*(0.5*11 + 0.5*10) + 0.25*5.2826087 = 9.1956522; a = -28.043478
    ctrl = PISaturation()
    ctrl.reset(1)
    first = make_inputs([10.0], [20.0], [10.0], dt=0.1)
    assert accel(ctrl, first) == pytest.approx([-47.17391304347826])
    assert accel(ctrl, make_inputs([12.0], [5.0], [10.0], dt=0.1)) == pytest.approx(
        [-28.04347826086957]
    )
    ctrl.reset(1)
    assert accel(ctrl, first) == pytest.approx([-47.17391304347826])


def test_pi_saturation_history_window_forgets_old_speeds() -> None:
    # v_catch=0, no leader: alpha = 1, beta = 0.5, v_cmd = 0.5*U + 0.5*v_cmd_prev.
    # speeds 1,2,3,4 with a 0.4 s window at dt = 0.1 (Flow keeps int(0.4/0.1) - 1 = 3 samples):
    # U = 1, 1.5, 2, mean(2,3,4) = 3 -> v_cmd = 0.5, 1.0, 1.5, 2.25 (2.0 without the window)
    ctrl = PISaturation(v_catch=0, history_time=0.4)
    ctrl.reset(1)
    for v in (1.0, 2.0, 3.0, 4.0):
        accel(ctrl, make_inputs([v], [INF], dt=0.1))
    assert ctrl.v_cmd == pytest.approx([2.25])


def test_pi_saturation_resizes_memory_when_group_size_changes() -> None:
    ctrl = PISaturation()
    ctrl.reset(2)
    out = accel(ctrl, make_inputs([10.0, 10.0, 10.0], [20.0] * 3, [10.0] * 3, dt=0.1))
    assert out == pytest.approx([-47.17391304347826] * 3)


def test_rl_and_sim_controllers_give_no_command() -> None:
    inp = make_inputs([1.0, 2.0], [10.0, INF])
    for ctrl in (RLController(), SimCarFollowingController()):
        out = accel(ctrl, inp)
        assert out.shape == (2,)
        assert np.all(np.isnan(out))
    assert RLController.is_rl and RLController.commands_sumo
    assert not SimCarFollowingController.commands_sumo and not SimCarFollowingController.is_rl
    assert not IDMController.is_rl and IDMController.commands_sumo


ALL_COMMANDING = [
    IDMController,
    OVMController,
    LinearOVM,
    BCMController,
    CFMController,
    BandoFTLController,
    GippsController,
    FollowerStopper,
    PISaturation,
]


@pytest.mark.parametrize("cls", ALL_COMMANDING)
def test_every_controller_returns_one_finite_value_per_vehicle(cls: type) -> None:
    rng = np.random.default_rng(3)
    n = 17
    h = rng.uniform(0.0, 80.0, n)
    h[::5] = INF
    inp = make_inputs(
        rng.uniform(0, 30, n),
        h,
        rng.uniform(0, 30, n),
        follower_headway=rng.uniform(0.5, 50, n),
        follower_speed=rng.uniform(0, 30, n),
    )
    ctrl = cls()
    ctrl.reset(n)
    out = accel(ctrl, inp)
    assert out.shape == (n,)
    assert out.dtype == np.float64
    assert np.all(np.isfinite(out))


def test_flow_defaults() -> None:
    idm = IDMController()
    assert (idm.v0, idm.T, idm.a, idm.b, idm.delta, idm.s0, idm.noise) == (30, 1, 1, 1.5, 4, 2, 0)
    ovm = OVMController()
    assert (ovm.alpha, ovm.beta, ovm.h_st, ovm.h_go, ovm.v_max) == (1, 1, 2, 15, 30)
    lin = LinearOVM()
    assert (lin.v_max, lin.adaptation, lin.h_st) == (30, 0.65, 5)
    bcm = BCMController()
    assert (bcm.k_d, bcm.k_v, bcm.k_c, bcm.d_des, bcm.v_des) == (1, 1, 1, 1, 8)
    bando = BandoFTLController()
    assert (bando.alpha, bando.beta, bando.h_st, bando.h_go, bando.v_max) == (0.5, 20, 2, 10, 32)
    assert bando.want_max_accel is False
    gipps = GippsController()
    assert (gipps.v0, gipps.acc, gipps.b, gipps.b_l, gipps.s0, gipps.tau) == (30, 1.5, -1, -1, 2, 1)
    fs = FollowerStopper()
    assert (fs.v_des, fs.dx_1_0, fs.dx_2_0, fs.dx_3_0) == (15, 4.5, 5.25, 6.0)
    assert (fs.d_1, fs.d_2, fs.d_3) == (1.5, 1.0, 0.5)
    pi = PISaturation()
    assert (pi.v_catch, pi.g_l, pi.g_u, pi.gamma, pi.history_time) == (1, 7, 30, 2, 38)


# --- noise ---------------------------------------------------------------------------------


def _ring_inputs(n: int, dt: float = 0.1) -> CarFollowingInputs:
    return make_inputs(np.full(n, 5.0), np.full(n, 12.0), np.full(n, 5.0), dt=dt)


def test_noise_is_reproducible_per_seed() -> None:
    ctrl = IDMController(noise=0.2)
    inp = _ring_inputs(22)
    a1, a2, b = accel(ctrl, inp, seed=7), accel(ctrl, inp, seed=7), accel(ctrl, inp, seed=8)
    assert np.array_equal(a1, a2)
    assert not np.allclose(a1, b)


def test_zero_noise_is_the_exact_formula_and_uses_no_randomness() -> None:
    inp = _ring_inputs(22)
    rng = np.random.default_rng(0)
    out = IDMController(noise=0).get_accel(inp, rng)
    exact = idm_accel(
        inp.speed, inp.headway, inp.leader_speed, v0=30, T=1, a=1, b=1.5, delta=4, s0=2
    )
    assert np.array_equal(out, exact)
    assert rng.bit_generator.state == np.random.default_rng(0).bit_generator.state


@pytest.mark.parametrize(("noise", "dt"), [(0.2, 0.1), (0.2, 0.4), (1.0, 0.1)])
def test_noise_std_is_sqrt_dt_times_noise(noise: float, dt: float) -> None:
    n = 200_000
    inp = _ring_inputs(n, dt=dt)
    base = accel(IDMController(), inp)
    noisy = accel(IDMController(noise=noise), inp, seed=12345)
    diff = noisy - base
    assert abs(diff.mean()) < 0.01 * noise
    assert diff.std() == pytest.approx(math.sqrt(dt) * noise, rel=0.03)


def test_lac_lags_towards_its_linear_command_and_keeps_memory_per_vehicle() -> None:
    from flowrun.controllers import LACController

    lac = LACController(k_1=0.3, k_2=0.4, h=1, tau=0.1)
    lac.reset(2)
    inputs = replace(
        make_inputs([10.0, 10.0], [20.0, np.inf], [12.0, 10.0], dt=0.05), length=np.full(2, 5.0)
    )
    # car 0: e_x = 20 - 5 - 1*10 = 5, e_v = 2 -> u = 0.3*5 + 0.4*2 = 2.3; a <- a + 0.5 (u - a)
    # car 1 has no leader: u = 0, stays at 0
    first = lac.get_accel(inputs, np.random.default_rng(0))
    assert first == pytest.approx([1.15, 0.0])
    second = lac.get_accel(inputs, np.random.default_rng(0))
    assert second == pytest.approx([1.725, 0.0])
    lac.reset(2)
    assert lac.get_accel(inputs, np.random.default_rng(0)) == pytest.approx([1.15, 0.0])
