"""The built-in ring environments: Gymnasium contract, seeding, Flow's observations and rewards."""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from pathlib import Path

import gymnasium
import libsumo
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import flowrun.envs  # registers flowrun/<Name>-v0
from flowrun.envs import Env, env_names
from flowrun.envs.rewards import desired_velocity
from flowrun.errors import ConfigError

RING_WAVE = Path(__file__).resolve().parent.parent / "configs" / "ring_wave.yaml"
BUILTIN = [
    "AccelEnv",
    "BottleneckAccelEnv",
    "BottleneckDesiredVelocityEnv",
    "BottleneckEnv",
    "DesiredVelocityEnv",
    "LaneChangeAccelEnv",
    "LaneChangeAccelPOEnv",
    "MergePOEnv",
    "TestEnv",
    "TrafficLightGridBenchmarkEnv",
    "TrafficLightGridEnv",
    "TrafficLightGridPOEnv",
    "WaveAttenuationEnv",
    "WaveAttenuationPOEnv",
]

pytestmark = pytest.mark.sumo


def make(name: str, **kwargs: object) -> Env:
    """A registered env, unwrapped, with a short horizon and no warm-up unless given."""
    kwargs.setdefault("horizon", 50)
    kwargs.setdefault("warmup_steps", 0)
    env = gymnasium.make(f"flowrun/{name}-v0", **kwargs).unwrapped
    assert isinstance(env, Env)
    return env


@pytest.fixture
def po_env() -> Iterator[Env]:
    env = make("WaveAttenuationPOEnv", horizon=200)
    yield env
    env.close()


def ring_x(env: Env, veh_id: str) -> float:
    """A car's ring position read from SUMO (edge start + lane position)."""
    edge = libsumo.vehicle.getRoadID(veh_id)
    return env.k.network.get_x(edge, libsumo.vehicle.getLanePosition(veh_id))


def test_every_builtin_env_is_registered_with_gymnasium():
    from flowrun.envs.registry import MULTIAGENT_ENVS  # PettingZoo envs: not Gymnasium's

    assert env_names() == sorted([*BUILTIN, *MULTIAGENT_ENVS])
    for name in BUILTIN:
        assert f"flowrun/{name}-v0" in gymnasium.registry


@pytest.mark.parametrize("name", BUILTIN)
def test_check_env_passes(name):
    env = make(name, render_mode="rgb_array")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # advice on asymmetric / unbounded Box spaces
            check_env(env, skip_render_check=False)
    finally:
        env.close()


def test_same_seed_same_episode_other_seed_other_ring():
    env = make("WaveAttenuationPOEnv", warmup_steps=30)
    try:
        runs = []
        for seed in (7, 7, 8):
            obs, _ = env.reset(seed=seed)
            first = obs.copy()
            for _ in range(20):
                obs, *_ = env.step(np.array([0.3], dtype=np.float32))
            runs.append((first, obs.copy(), env.k.network.length(), env.k.vehicle.speed.copy()))
        (a0, a1, la, va), (b0, b1, lb, vb), (c0, _, lc, _) = runs
        assert np.array_equal(a0, b0) and np.array_equal(a1, b1) and np.array_equal(va, vb)
        assert la == lb
        assert (lc, c0.tolist()) != (la, a0.tolist())
    finally:
        env.close()


def test_step_before_reset_raises():
    env = make("WaveAttenuationPOEnv")
    try:
        with pytest.raises(gymnasium.error.ResetNeeded):
            env.step(np.zeros(1, dtype=np.float32))
    finally:
        env.close()
    wrapped = gymnasium.make("flowrun/WaveAttenuationPOEnv-v0")
    try:
        with pytest.raises(gymnasium.error.ResetNeeded):
            wrapped.step(np.zeros(1, dtype=np.float32))
    finally:
        wrapped.close()


def test_make_with_defaults_is_the_stabilizing_the_ring_task():
    env = gymnasium.make("flowrun/WaveAttenuationPOEnv-v0")
    try:
        inner = env.unwrapped
        assert isinstance(inner, flowrun.envs.WaveAttenuationPOEnv)
        assert inner.env_params.horizon == 3000
        assert inner.env_params.warmup_steps == 750
        assert list(inner.env_params.additional_params["ring_length"]) == [220, 270]
        assert inner.initial_vehicles.num_vehicles == 22
        assert inner.initial_vehicles.num_rl_vehicles == 1
        obs, info = env.reset(seed=0)
        assert obs.shape == (3,) and obs.dtype == np.float32
        assert info["time"] == pytest.approx(75.2)  # Flow's start + insertion steps + 750 warm-up
        assert env.render() is None  # no render_mode asked
    finally:
        env.close()


def test_make_takes_a_config_file_overrides_and_render_mode():
    env = gymnasium.make(
        "flowrun/WaveAttenuationPOEnv-v0",
        config=RING_WAVE,
        overrides=["env.warmup_steps=0", "vehicles[0].count=10"],
        render_mode="rgb_array",
        horizon=5,
    )
    try:
        inner = env.unwrapped
        assert inner.initial_vehicles.num_vehicles == 11
        assert inner.env_params.horizon == 5
        env.reset(seed=1)
        frame = env.render()
        assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
        truncated = False
        for _ in range(5):
            _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        assert truncated and not terminated
    finally:
        env.close()


def test_make_rejects_an_unknown_override():
    with pytest.raises(ConfigError, match="did you mean 'warmup_steps'"):
        gymnasium.make("flowrun/AccelEnv-v0", overrides=["env.warmup_step=3"])


def test_ring_length_is_redrawn_in_220_270_at_each_reset():
    env = make("WaveAttenuationEnv")
    try:
        lengths = []
        for _ in range(6):
            env.reset()
            length = env.k.network.length()
            lengths.append(length)
            # the cars fill the new ring (bunching 20 m): the last one is close to its end
            assert env.k.vehicle.position.max() == pytest.approx((length - 20) * 21 / 22, abs=1e-6)
        assert all(220 <= x <= 270 and x == int(x) for x in lengths)
        assert len(set(lengths)) >= 3
    finally:
        env.close()


def test_partial_observation_is_flows(po_env):
    po_env.reset(seed=3)
    for _ in range(40):
        obs, *_ = po_env.step(np.array([0.5], dtype=np.float32))
    leader, gap_minus_min_gap = libsumo.vehicle.getLeader("rl_0", 1000.0)
    v_av = libsumo.vehicle.getSpeed("rl_0")
    v_lead = libsumo.vehicle.getSpeed(leader)
    length = po_env.k.network.length()
    gap = (ring_x(po_env, leader) - ring_x(po_env, "rl_0")) % length
    # SUMO's bumper-to-bumper gap plus the leader's length and the ego's minGap
    assert gap == pytest.approx(gap_minus_min_gap + 5.0 + 2.5, abs=1e-6)
    expected = [v_av / 15, (v_lead - v_av) / 15, gap / 270]
    np.testing.assert_allclose(obs, expected, rtol=1e-6, atol=1e-7)
    assert v_av > 1.0  # the AV moves, so the check is not about zeros


@pytest.mark.parametrize(("action", "applied"), [(0.5, 0.5), (-0.25, -0.25), (5.0, 1.0)])
def test_wave_attenuation_reward_is_speed_minus_accel_penalty(po_env, action, applied):
    po_env.reset(seed=0)
    for _ in range(10):
        _, reward, _, _, info = po_env.step(np.array([action], dtype=np.float32))
    speeds = [libsumo.vehicle.getSpeed(v) for v in po_env.k.vehicle.get_ids()]
    expected = 4 * np.mean(speeds) / 20 - 4 * abs(applied)
    assert reward == pytest.approx(expected, abs=1e-9)
    terms = info["reward_terms"]
    assert terms["speed"] == pytest.approx(4 * np.mean(speeds) / 20, abs=1e-9)
    assert terms["accel_penalty"] == pytest.approx(-4 * abs(applied))
    assert sum(terms.values()) == pytest.approx(reward)


def test_wave_attenuation_full_observation_is_speeds_and_positions():
    env = make("WaveAttenuationEnv")
    try:
        env.reset(seed=2)
        for _ in range(30):
            obs, *_ = env.step(np.array([1.0], dtype=np.float32))
        ids = env.k.vehicle.get_ids()
        speed = np.array([libsumo.vehicle.getSpeed(v) for v in ids]) / 30
        pos = np.array([ring_x(env, v) for v in ids]) / env.k.network.length()
        np.testing.assert_allclose(obs, np.concatenate([speed, pos]), rtol=1e-6, atol=1e-7)
    finally:
        env.close()


def test_accel_env_observation_and_desired_velocity_reward():
    env = make("AccelEnv")
    try:
        env.reset(seed=4)
        for _ in range(30):
            obs, reward, _, _, info = env.step(np.array([1.0], dtype=np.float32))
        ids = env.k.vehicle.get_ids()
        v = np.array([libsumo.vehicle.getSpeed(i) for i in ids])
        pos = np.array([ring_x(env, i) for i in ids]) / env.k.network.length()
        np.testing.assert_allclose(obs, np.concatenate([v / 30, pos]), rtol=1e-6, atol=1e-7)
        # Flow: max(||t|| - ||v - t||, 0) / ||t|| with t = 10 m/s for every car
        t = np.full(v.size, 10.0)
        expected = max(np.linalg.norm(t) - np.linalg.norm(v - t), 0) / np.linalg.norm(t)
        assert reward == pytest.approx(expected, rel=1e-6)
        assert info["reward_terms"] == {"desired_velocity": pytest.approx(reward)}
        assert desired_velocity(np.full(4, 10.0), 10.0) == pytest.approx(1.0)
        assert desired_velocity(np.full(4, 10.0), 10.0, fail=True) == 0.0
    finally:
        env.close()


def test_lane_change_env_changes_lane_and_pays_for_it():
    env = make(
        "LaneChangeAccelEnv",
        overrides=["vehicles[1].count=10", "initial.lanes_distribution=1"],
    )
    try:
        obs, _ = env.reset(seed=0)
        assert env.action_space.shape == (2,) and obs.shape == (33,)
        assert env.k.vehicle.get_lane("rl_0") == 0
        obs, reward, _, _, info = env.step(np.array([0.5, 1.0], dtype=np.float32))
        assert env.k.vehicle.get_lane("rl_0") == 1
        assert obs[22] == pytest.approx(1 / 2)  # lane / number of lanes (Flow)
        assert info["reward_terms"]["lane_change_penalty"] == pytest.approx(-0.1)
        assert reward == pytest.approx(info["reward_terms"]["desired_velocity"] - 0.1)
        # asking again right away is ignored: one change per lane_change_duration (5 s)
        obs, reward, _, _, info = env.step(np.array([0.5, -1.0], dtype=np.float32))
        assert env.k.vehicle.get_lane("rl_0") == 1
        assert info["reward_terms"]["lane_change_penalty"] == 0.0
        # a new episode starts with a fresh lane-change timer
        env.reset(seed=0)
        env.step(np.array([0.0, 1.0], dtype=np.float32))
        assert env.k.vehicle.get_lane("rl_0") == 1
    finally:
        env.close()


def run_until_done(env: Env, action: float, limit: int) -> tuple[int, float, bool, bool, dict]:
    """Step with a constant action until the episode ends; the last step's results."""
    act = np.array([action], dtype=np.float32)
    for n in range(1, limit + 1):
        _, reward, terminated, truncated, info = env.step(act)
        if terminated or truncated:
            return n, reward, terminated, truncated, info
    return limit, reward, terminated, truncated, info


def test_collision_terminates_and_horizon_truncates():
    env = make(
        "WaveAttenuationPOEnv",
        horizon=300,
        overrides=[
            "env.additional_params.max_accel=3",
            "vehicles[0].car_following.speed_mode=aggressive",  # the AV's group
        ],
    )
    try:
        env.reset(seed=0)
        # the AV accelerates at 3 m/s^2 into its leader; speed_mode 'aggressive' lets it crash
        steps, reward, terminated, truncated, info = run_until_done(env, 3.0, 300)
        assert terminated and not truncated, f"no crash in {steps} steps"
        assert info["crash"] is True and info["collisions"] >= 1
        assert reward == 0.0  # Flow: no reward on the step of a crash
        with pytest.raises(gymnasium.error.ResetNeeded):
            env.step(np.zeros(1, dtype=np.float32))

        env.reset(seed=0)  # the AV stays put: no crash, the horizon ends the episode
        steps, _, terminated, truncated, info = run_until_done(env, 0.0, 400)
        assert truncated and not terminated and steps == 300
        assert info["crash"] is False and info["collisions"] == 0
    finally:
        env.close()


def test_default_speed_mode_keeps_a_reckless_av_from_crashing():
    env = make("WaveAttenuationPOEnv", horizon=300, overrides=["env.additional_params.max_accel=3"])
    try:
        assert env.network.vehicles.get_type("rl").car_following_params.speed_mode == 25
        env.reset(seed=0)
        steps, _, terminated, truncated, info = run_until_done(env, 3.0, 300)
        assert truncated and not terminated and steps == 300
        assert info["collisions"] == 0
    finally:
        env.close()


def test_info_reports_speed_time_and_reward_terms(po_env):
    _, info = po_env.reset(seed=0)
    assert info["reward_terms"] == {} or set(info["reward_terms"]) == {"speed", "accel_penalty"}
    _, _, _, _, info = po_env.step(np.array([0.1], dtype=np.float32))
    assert set(info) >= {"crash", "mean_speed", "collisions", "teleports", "time", "reward_terms"}
    assert set(info["reward_terms"]) == {"speed", "accel_penalty"}
    assert info["mean_speed"] == pytest.approx(
        np.mean([libsumo.vehicle.getSpeed(v) for v in po_env.k.vehicle.get_ids()])
    )
    assert info["time"] == pytest.approx(0.3)  # Flow's start + insertion steps + 1


def test_sims_per_step_holds_the_action_over_several_simulation_steps():
    env = make("WaveAttenuationPOEnv", sims_per_step=5)
    try:
        env.reset(seed=0)
        env.step(np.array([1.0], dtype=np.float32))
        assert env.k.simulation.time == pytest.approx(0.7)  # start + insertion + 5 steps
        assert env.k.vehicle.get_speed("rl_0") == pytest.approx(0.5, abs=1e-9)
    finally:
        env.close()


def test_a_second_env_stops_the_first_and_the_first_asks_for_reset(caplog):
    first, second = make("AccelEnv"), make("WaveAttenuationPOEnv")
    try:
        first.reset(seed=0)
        second.reset(seed=0)
        assert "already running" in caplog.text
        with pytest.raises(gymnasium.error.ResetNeeded, match="another environment"):
            first.step(np.zeros(1, dtype=np.float32))
        first.reset(seed=0)  # takes the simulation back
        _, _, terminated, _, info = first.step(np.zeros(1, dtype=np.float32))
        assert not terminated and info["time"] == pytest.approx(0.3)
        with pytest.raises(gymnasium.error.ResetNeeded):
            second.step(np.zeros(1, dtype=np.float32))
    finally:
        first.close()
        second.close()
        first.close()  # close is idempotent


def test_warmup_runs_before_the_first_observation():
    env = make("WaveAttenuationPOEnv", warmup_steps=100)
    try:
        obs, info = env.reset(seed=0)
        assert info["time"] == pytest.approx(10.2)
        assert obs[0] * 15 == pytest.approx(libsumo.vehicle.getSpeed("rl_0"), abs=1e-5)
        assert not math.isclose(float(obs[0]), 0.0)
    finally:
        env.close()


def test_null_ring_length_keeps_the_configured_ring():
    env = make("WaveAttenuationPOEnv", overrides=["env.additional_params.ring_length=null"])
    try:
        for seed in (0, 1):
            obs, _ = env.reset(seed=seed)
            assert env.k.network.length() == 230
        leader = env.k.vehicle.get_leader("rl_0")
        gap = (ring_x(env, leader) - ring_x(env, "rl_0")) % 230
        assert obs[2] == pytest.approx(gap / 230, rel=1e-6)  # Flow: divided by the ring length
    finally:
        env.close()


def test_bad_ring_length_is_reported_when_the_env_is_made():
    with pytest.raises(ConfigError, match=r"ring_length: expected \[low, high\]"):
        make("WaveAttenuationEnv", overrides=["env.additional_params.ring_length=[270, 220]"])
