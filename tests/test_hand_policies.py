"""The pure rules of ``bench/hand_policies.py``: each hand policy's action from given state."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import numpy as np

NAN = float("nan")


def _bench() -> ModuleType:
    path = Path(__file__).resolve().parent.parent / "bench" / "hand_policies.py"
    spec = importlib.util.spec_from_file_location("hand_policies", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("hand_policies", module)
    spec.loader.exec_module(module)
    return module


hp = _bench()


def test_cap_deltas_bring_the_slowest_av_to_its_target_within_the_action_space() -> None:
    min_caps = np.array([23.0, 6.0, 5.0, NAN, 10.0])
    targets = np.array([5.0, 5.0, 5.0, 5.0, NAN])
    # 23 -> 5 is cut to -1.5; 6 -> 5 is -1; at 5 already: 0; no AV: 0; no target: release (+1.5)
    assert np.allclose(hp.cap_deltas(min_caps, targets, -1.5, 1.5), [-1.5, -1.0, 0.0, 0.0, 1.5])


def test_fixed_time_switches_every_light_first_then_each_period_after_its_offset() -> None:
    offsets = np.array([0.0, 5.0])
    switched = {t: hp.fixed_time_switch(t, 10, offsets) > 0 for t in range(26)}
    assert switched[0].all()  # the first step takes every light over
    assert [t for t in range(1, 26) if switched[t][0]] == [10, 20]
    assert [t for t in range(1, 26) if switched[t][1]] == [15, 25]


def test_queue_rule_switches_only_a_settled_green_facing_a_longer_red_queue() -> None:
    green = np.array([1.0, 1.0, 3.0, 1.0])
    red = np.array([4.0, 4.0, 3.0, 4.0])
    since = np.array([11.0, 6.0, 20.0, 20.0])
    yellow = np.array([0.0, 0.0, 0.0, 1.0])
    # light 0 switches; 1 has not held its green long enough; 2 has no longer queue; 3 is yellow
    assert list(hp.queue_switch(green, red, since, yellow, 8.0)) == [1.0, -1.0, -1.0, -1.0]


def test_meter_engages_above_its_threshold_and_releases_at_or_below_the_lower_one() -> None:
    assert hp.meter_engaged(False, 12.5, 12.0, 8.0)
    assert not hp.meter_engaged(False, 10.0, 12.0, 8.0)  # not yet engaged: stays off
    assert hp.meter_engaged(True, 10.0, 12.0, 8.0)  # engaged: holds until 8
    assert not hp.meter_engaged(True, 8.0, 12.0, 8.0)
    assert not hp.meter_engaged(True, 12.0, 12.0, 12.0)  # no hysteresis: on above 12 only


f8 = hp.hand_figure_eight
LOOP = f8.Loop(length=420.0, crossings=(30.0, 240.0), max_speed=30.0, av=2)


def _obs(speeds: list[float], xs: list[float]) -> np.ndarray:
    return np.array([*(np.array(speeds) / 30.0), *(np.array(xs) / 420.0)])


def test_leader_gap_wraps_around_the_loop() -> None:
    gap, j = f8.leader_gap(np.array([400.0, 10.0, 200.0]), 0, 420.0)
    assert (round(gap, 6), j) == (25.0, 1)  # 30 m ahead across x = 0, minus a 5 m car


def test_crossing_gap_follows_the_last_car_due_first_on_the_other_link() -> None:
    # the AV at x 200 is 40 m from its link (starts at 240); cars 0 and 1 head for the other
    # link (30): car 0 is 10 m from it, car 1 is on it 5 m past its start; car 3 is due later
    x = np.array([20.0, 35.0, 200.0, 400.0])
    gap, j = f8.crossing_gap(x, 2, LOOP, 14.4)
    assert j == 0 and abs(gap - (40.0 - 10.0 - 14.4)) < 1e-9
    # a car on its own link (5 m past the start of 240) is committed: no crossing leader
    assert f8.crossing_gap(np.array([20.0, 35.0, 245.0]), 2, LOOP, 14.4)[0] == float("inf")


def test_gap_speed_rule_stands_close_behind_and_drives_the_speed_its_gap_allows() -> None:
    assert f8.gap_speed_accel(30.0, 0.0, 90.0, 15.0) == -3.0  # near leader: stands (brakes)
    assert abs(f8.gap_speed_accel(120.0, 0.0, 90.0, 15.0) - 2.0) < 1e-9  # leader away: sets off
    assert abs(f8.gap_speed_accel(240.0, 8.0, 90.0, 15.0) - 2.0) < 1e-9  # wants 10 m/s
    assert f8.gap_speed_accel(1000.0, 0.0, 90.0, 15.0) == 3.0  # clipped to the action space


def test_gap_speed_rule_on_an_observation_and_its_linear_form_across_x_zero() -> None:
    rule = f8.Rule("gap-speed", s0=90.0, t_gap=15.0)
    linear = f8.Rule("gap-speed", s0=90.0, t_gap=15.0, linear=True)
    # the AV (last) at x 300 m, 8 m/s; its leader (car 0) 245 m ahead, past x = 0 at 125 m
    obs = _obs([8.0, 8.0, 8.0], [125.0, 200.0, 300.0])
    assert abs(rule.accel(obs, LOOP) - ((245.0 - 5.0 - 90.0) / 15.0 - 8.0)) < 1e-9
    assert linear.accel(obs, LOOP) == -3.0  # x_leader - x_AV = -175 m: it brakes instead
    ahead = _obs([8.0, 8.0, 8.0], [345.0, 200.0, 100.0])  # the same gap without the wrap
    assert abs(linear.accel(ahead, LOOP) - rule.accel(ahead, LOOP)) < 1e-9


def test_idm_equilibrium_speed_is_where_the_humans_idm_does_not_accelerate() -> None:
    from flowrun.controllers.car_following_formulas import idm_accel

    v = f8.idm_equilibrium_speed(10.12)
    assert 8.0 < v < 8.2
    a = idm_accel(np.array(v), np.array(10.12), np.array(v), v0=30.0, T=1.0, a=1.0, b=1.5,
                  delta=4.0, s0=2.0)  # fmt: skip
    assert abs(float(a)) < 1e-6


def test_stream_switch_gap_is_the_shortest_time_between_the_two_links_passages() -> None:
    # car 0 passes link 0's point (10 m) at 1.0 s, car 1 link 1's (100 m) at 2.0 s and car 2
    # link 1's at 2.5 s: one switch of streams, 1.0 s after the other
    xs = np.array([[8.0, 96.0, 50.0], [9.5, 97.0, 60.0], [10.5, 98.5, 70.0], [11.0, 99.5, 80.0],
                   [11.5, 100.5, 90.0], [12.0, 101.0, 100.5]])  # fmt: skip
    assert f8.stream_switch_gap(xs, (10.0, 100.0), 200.0, 0.5) == 1.0  # 2 steps of 0.5 s
    # a position that steps back a little (x at a link's end) is not a passage
    back = np.array([[12.0, 50.0], [9.0, 50.0], [11.0, 50.0]])
    assert f8.stream_switch_gap(back, (10.0, 100.0), 200.0, 0.1) == float("inf")


def test_a_column_within_half_the_loop_fits_and_evenly_spread_cars_never_do() -> None:
    length = 421.94
    assert f8.steady_layout_fits(15.0, 8.0, length, 1.6)  # column of 13 x 15 m < 211 m
    assert not f8.steady_layout_fits(length / 14, 10.0, length, 0.1)  # k and k + 7 meet
    speed, headway = f8.best_steady_layout(length, 1.6)
    assert 13 * headway < length / 2 and 8.0 < speed < 8.4  # the best layout is one column
