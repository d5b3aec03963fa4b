"""``AccelEnv`` on the figure eight and ``MergePOEnv`` on the merge: Gymnasium contract, Flow's
observations, actions and rewards, and the traffic each scenario is known for.

Real SUMO, seeded, short; the reward formulas are also checked on hand-worked numbers.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Any

import libsumo
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from flowrun.config.model import ExperimentConfig
from flowrun.envs import AccelEnv, Env, MergePOEnv
from flowrun.envs.defaults import merge0_config
from flowrun.envs.factory import make_env
from flowrun.envs.merge import merge_reward, time_headway_penalty
from flowrun.envs.rewards import desired_velocity
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
UPSTREAM = ("inflow_highway", "left")
APPROACHES = ("bottom", "right")  # the figure eight's edges into the crossing, 30 m long
ALL_HUMAN_MERGE = "network.inflows.1.veh_type=human"  # the AV inflow driven by humans


def load(name: str, *overrides: str) -> ExperimentConfig:
    """``configs/<name>.yaml`` with ``a.b=value`` overrides."""
    return load_config(CONFIGS / f"{name}.yaml", list(overrides))


@contextmanager
def env_of(name: str, *overrides: str) -> Iterator[Any]:
    """The env of ``configs/<name>.yaml`` with overrides, closed afterwards."""
    env = make_env(load(name, *overrides))
    try:
        yield env
    finally:
        env.close()


def record_commands(env: Env) -> list[tuple[list[str], list[float]]]:
    """Every ``apply_acceleration`` (by id) or ``apply_acceleration_rows`` call the env makes
    from now on (ids, accelerations)."""
    calls: list[tuple[list[str], list[float]]] = []
    vk = env.k.vehicle
    apply, apply_rows = vk.apply_acceleration, vk.apply_acceleration_rows

    def spy(ids: Any, accs: Any) -> None:
        ids = [ids] if isinstance(ids, str) else list(ids)
        calls.append((ids, np.broadcast_to(np.asarray(accs, float), (len(ids),)).tolist()))
        apply(ids, accs)

    def spy_rows(rows: Any, accs: Any) -> None:
        calls.append(([vk.table.ids[r] for r in rows.tolist()], np.asarray(accs, float).tolist()))
        apply_rows(rows, accs)

    vk.apply_acceleration = spy  # type: ignore[method-assign,assignment]
    vk.apply_acceleration_rows = spy_rows  # type: ignore[method-assign]
    return calls


# ------------------------------------------------------------------ formulas, no SUMO


def test_time_headway_penalty_on_hand_worked_numbers() -> None:
    # h/v = 5/10 = 0.5 s -> (0.5 - 1)/1 = -0.5; 30/10 = 3 s -> 0; 2/4 = 0.5 s -> -0.5;
    # a car standing still is left out
    headways = np.array([5.0, 30.0, 2.0, 1.0])
    speeds = np.array([10.0, 10.0, 4.0, 0.0])
    assert time_headway_penalty(headways, speeds) == pytest.approx(-1.0)
    assert time_headway_penalty(np.array([5.0]), np.array([10.0]), t_min=2.0) == pytest.approx(
        (0.5 - 2.0) / 2.0
    )
    assert time_headway_penalty(np.zeros(0), np.zeros(0)) == 0.0


def test_merge_reward_terms_and_floor_at_zero() -> None:
    speeds = np.array([20.0, 10.0])
    # |t| = 20*sqrt(2); |v - t| = 10 -> (28.284 - 10) / 28.284
    r_v = (20 * math.sqrt(2) - 10) / (20 * math.sqrt(2))
    terms = merge_reward(speeds, 20.0, np.array([5.0]), np.array([10.0]))
    assert terms["desired_velocity"] == pytest.approx(r_v, rel=1e-6)
    assert terms["headway_penalty"] == pytest.approx(0.1 * -0.5)
    # many tailgating AVs: the sum goes negative, the env floors the reward at 0
    crowded = merge_reward(np.array([1.0]), 20.0, np.full(20, 0.5), np.full(20, 10.0))
    assert sum(crowded.values()) < 0
    assert merge_reward(speeds, 20.0, np.array([5.0]), np.array([10.0]), fail=True) == {
        "desired_velocity": 0.0,
        "headway_penalty": 0.0,
    }


# ------------------------------------------------------------------ Gymnasium contract


@pytest.mark.sumo
@pytest.mark.parametrize("name", ["figure_eight_rl", "merge"])
def test_check_env_passes_on_the_open_scenarios(name: str) -> None:
    with env_of(name, "env.horizon=30") as env, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=True)
    advice = "symmetric and normalized"  # Flow's asymmetric acceleration bounds
    assert [str(w.message) for w in caught if advice not in str(w.message)] == []


@pytest.mark.sumo
def test_merge_po_env_is_registered_with_flows_merge0_as_default() -> None:
    import gymnasium

    env = gymnasium.make("flowrun/MergePOEnv-v0", horizon=5).unwrapped
    try:
        assert isinstance(env, MergePOEnv)
        assert env.num_rl == 5 and env.observation_space.shape == (25,)
        assert env.network.network_type == "merge" and env.env_params.sims_per_step == 2
    finally:
        env.close()


def test_merge0_default_is_the_same_experiment_as_configs_merge_yaml() -> None:
    cfg = load("merge")
    default = merge0_config()
    assert (default.sim, default.env, default.vehicles, default.initial) == (
        cfg.sim,
        cfg.env,
        cfg.vehicles,
        cfg.initial,
    )
    assert default.network.net_params.additional_params == cfg.network.net_params.additional_params
    flows = [f for f in (default.network.net_params.inflows, cfg.network.net_params.inflows)]
    assert flows[0] is not None and flows[1] is not None
    assert flows[0].get() == flows[1].get()


@pytest.mark.sumo
@pytest.mark.parametrize("num_rl", [0, 2.5, "two"])
def test_merge_num_rl_must_be_a_whole_number_of_avs(num_rl: object) -> None:
    with pytest.raises(ConfigError, match="num_rl"):
        make_env(load("merge", f"env.additional_params.num_rl={num_rl}"))


# ------------------------------------------------------------------ MergePOEnv


@pytest.mark.sumo
def test_merge_obs_keeps_its_size_and_fifo_order_while_avs_come_and_go() -> None:
    actions = np.array([1.0, 0.6], dtype=np.float32)  # distinct, and the AVs keep moving
    with env_of("merge", "env.additional_params.num_rl=2") as env:
        obs, _ = env.reset(seed=0)
        calls = record_commands(env)
        entered: list[str] = []  # AVs in order of arrival in the network
        slot: dict[str, int] = {}
        left_while_controlled = promoted = 0
        counts = set()
        for _ in range(250):
            before = list(env.rl_veh)
            queued_before = set(env.rl_queue)
            calls.clear()
            obs, _, terminated, _, _ = env.step(actions)
            assert not terminated
            assert obs.shape == (10,) and env.observation_space.contains(obs)
            vk = env.k.vehicle
            rl_now = vk.get_rl_ids()
            entered += [v for v in rl_now if v not in entered]
            counts.add(len(rl_now))
            # the controlled AVs are the first num_rl in line; the rest wait in the queue
            assert len(env.rl_veh) == min(2, len(rl_now))
            line = env.rl_veh + list(env.rl_queue)
            assert sorted(line) == sorted(rl_now)
            assert line == [v for v in entered if v in rl_now]  # first come, first served
            for i, v in enumerate(env.rl_veh):  # a controlled AV never moves back in line
                assert slot.get(v, i) >= i
                slot[v] = i
            left_while_controlled += sum(v not in rl_now for v in before)
            promoted += len(queued_before & set(env.rl_veh))
            # empty places observe zeros
            assert not obs[5 * len(env.rl_veh) :].any()
            # actions: the i-th to the i-th controlled AV, only while it is in the network
            commanded = {v: a for ids, accs in calls for v, a in zip(ids, accs, strict=True)}
            assert set(commanded) <= set(before)
            for i, v in enumerate(before):
                if v in commanded:
                    assert commanded[v] == pytest.approx(actions[i])
            assert all(v in commanded for v in before if v in rl_now)
        assert left_while_controlled > 0 and promoted > 0
        assert min(counts) < 2 < max(counts)


@pytest.mark.sumo
def test_merge_obs_of_an_av_equals_the_kernel_getters_and_sumos_leader() -> None:
    with env_of("merge", "env.additional_params.num_rl=1") as env:
        env.reset(seed=0)
        checked = 0
        for _ in range(200):
            obs, *_ = env.step(np.zeros(1, dtype=np.float32))
            if not env.rl_veh:
                continue
            rl = env.rl_veh[0]
            vk = env.k.vehicle
            lead, follow = vk.get_leader(rl), vk.get_follower(rl)
            if lead is None or follow is None:
                continue
            vmax, length = env.k.network.max_speed(), env.k.network.length()
            v = vk.get_speed(rl)
            expected = [
                v / vmax,
                (vk.get_speed(lead) - v) / vmax,
                vk.get_headway(rl) / length,
                (v - vk.get_speed(follow)) / vmax,
                vk.get_tailway(rl) / length,
            ]
            np.testing.assert_allclose(obs, expected, rtol=1e-6, atol=1e-7)
            # the gap is SUMO's own (getLeader's gap excludes the ego's minGap)
            sumo_lead, gap = libsumo.vehicle.getLeader(rl, length)
            assert sumo_lead == lead
            min_gap = libsumo.vehicle.getMinGap(rl)
            assert vk.get_headway(rl) == pytest.approx(gap + min_gap, abs=1e-6)
            # on one road Flow's gap from absolute positions is the same number
            if vk.get_edge(rl) == vk.get_edge(lead) == "left":
                flow_gap = vk.get_x_by_id(lead) - vk.get_x_by_id(rl) - vk.get_length(rl)
                assert vk.get_headway(rl) == pytest.approx(flow_gap, abs=1e-6)
            assert env.leader == [lead] and env.follower == [follow]
            checked += 1
        assert checked > 20


@pytest.mark.sumo
def test_merge_reward_is_flows_formula_of_the_kernel_state() -> None:
    # AVs whose safe-speed check allows 0.3 s time gaps: full throttle makes them tailgate
    with env_of("merge", "vehicles.1.car_following.tau=0.3") as env:
        env.reset(seed=0)
        rewards = []
        for _ in range(150):
            _, reward, *_ = env.step(np.full(5, 1.5, dtype=np.float32))
            vk = env.k.vehicle
            v_all = np.array(vk.get_speed(vk.get_ids()))
            penalty = 0.0
            for rl in env.rl_veh:
                v = vk.get_speed(rl)
                if vk.get_leader(rl) is not None and v > 0:
                    penalty += min((max(vk.get_headway(rl) / v, 0) - 1) / 1, 0)
            expected = max(desired_velocity(v_all, 20.0) + 0.1 * penalty, 0.0)
            assert reward == pytest.approx(expected, abs=1e-12)
            rewards.append((reward, penalty))
        assert any(p < 0 for _, p in rewards)  # the penalty is exercised
        env.env_params = replace(env.env_params, evaluate=True)
        assert env.compute_reward(None, fail=False) == pytest.approx(
            float(np.mean(env.k.vehicle.speed))
        )


@pytest.mark.sumo
def test_all_human_merge_shows_stop_and_go_upstream() -> None:
    """Merging cars make highway cars brake; the braking comes back as waves upstream:
    cars on ``inflow_highway``/``left`` stop, go, and stop again."""
    with env_of("merge", ALL_HUMAN_MERGE) as env:
        env.reset(seed=0)
        history: dict[str, list[float]] = {}
        spread = []
        for step in range(200):
            _, _, terminated, _, info = env.step(None)
            assert not terminated
            vk = env.k.vehicle
            up = [(v, s) for v, e, s in zip(vk.table.ids, vk.edges, vk.speed.tolist(),
                                            strict=True) if e in UPSTREAM]  # fmt: skip
            for v, s in up:
                history.setdefault(v, []).append(s)
            if step >= 100 and len(up) > 2:
                spread.append(float(np.std([s for _, s in up])))
        assert info["collisions"] == 0
    lowest = min(min(h) for h in history.values())
    assert lowest < 1.0  # near-stops
    assert float(np.median(spread)) > 2.0  # speeds differ a lot along the road
    stop_and_go = [v for v, h in history.items() if stop_go_cycles(h) >= 2]
    assert len(stop_and_go) >= 10


def stop_go_cycles(speeds: list[float], slow: float = 4.0, fast: float = 8.0) -> int:
    """How often a car slowed below ``slow`` m/s again after recovering above ``fast``."""
    cycles, state = 0, "free"
    for s in speeds:
        if s < slow and state != "slow":
            cycles += state == "go"
            state = "slow"
        elif s > fast and state == "slow":
            state = "go"
    return cycles


# ------------------------------------------------------------------ AccelEnv, figure eight


@pytest.mark.sumo
def test_figure_eight_of_14_idm_cars_runs_1500_steps_and_queues_at_the_crossing() -> None:
    with env_of("figure_eight") as env:
        env.reset(seed=0)
        queued_steps = longest = 0
        for _ in range(1500):
            _, _, terminated, truncated, info = env.step(None)
            assert not terminated
            vk = env.k.vehicle
            # slow cars just before the crossing (last 20 m of its approaches) or on it
            lane_pos = vk.lane_pos.tolist()
            near = np.array(
                [e.startswith(":center") or (e in APPROACHES and p > 10)
                 for e, p in zip(vk.edges, lane_pos, strict=True)]
            )  # fmt: skip
            queued = int(np.count_nonzero(near & (vk.speed < 1.0)))
            queued_steps += queued > 0
            longest = max(longest, queued)
        assert truncated and env.k.vehicle.num_vehicles == 14
        assert (info["collisions"], info["teleports"]) == (0, 0)
        assert queued_steps > 100 and longest >= 2
        assert info["mean_speed"] < 8.0  # far below the 30 m/s limit and IDM's v0


@pytest.mark.sumo
def test_accel_env_on_the_figure_eight_observes_every_car_and_drives_the_av() -> None:
    with env_of("figure_eight_rl") as env:
        assert isinstance(env, AccelEnv)
        assert env.observation_space.shape == (28,) and env.action_space.shape == (1,)
        env.reset(seed=0)
        calls = record_commands(env)
        for k in range(60):
            calls.clear()
            action = np.array([math.sin(k / 5)], dtype=np.float32)
            obs, reward, *_ = env.step(action)
            assert calls == [(["rl_0"], [pytest.approx(float(action[0]))])]
        vk = env.k.vehicle
        ids = vk.get_ids()
        assert ids[-1] == "rl_0" and env.sorted_ids == ids
        speeds = np.array(vk.get_speed(ids))
        xs = np.array([vk.get_x_by_id(v) for v in ids])
        expected = np.concatenate([speeds / 30.0, xs / env.k.network.length()])
        np.testing.assert_allclose(obs, np.clip(expected, 0, 1), rtol=1e-6)
        t = 20.0
        best = t * math.sqrt(14)
        assert reward == pytest.approx(max(best - float(np.linalg.norm(speeds - t)), 0.0) / best)


@pytest.mark.sumo
def test_accel_env_keeps_flows_absolute_positions_and_sorts_by_them() -> None:
    with env_of("figure_eight_rl", "env.additional_params.sort_vehicles=true") as env:
        env.reset(seed=0)
        vk = env.k.vehicle
        length = env.k.network.length()
        # Flow's bookkeeping by hand: starts at x, then adds each change of x, modulo L,
        # updated before each simulation step (so from the positions one step earlier)
        absolute = {v: vk.get_x_by_id(v) for v in vk.get_ids()}
        prev = dict(absolute)
        assert env.absolute_position == pytest.approx(absolute)
        wrapped = False
        for _ in range(400):
            x = {v: vk.get_x_by_id(v) for v in vk.get_ids()}
            for v, xv in x.items():
                absolute[v] = (absolute[v] + xv - prev[v]) % length
                wrapped |= xv < prev[v]
                prev[v] = xv
            obs, *_ = env.step(np.zeros(1, dtype=np.float32))
            assert env.absolute_position == pytest.approx(absolute, abs=1e-9)
        assert wrapped  # some car went round the loop
        order = sorted(absolute, key=absolute.__getitem__)
        assert env.sorted_ids == order
        speeds = np.array(vk.get_speed(order)) / env.k.network.max_speed()
        np.testing.assert_allclose(obs[:14], speeds, rtol=1e-6)
