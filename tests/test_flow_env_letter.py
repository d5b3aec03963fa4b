"""Flow's environments to the letter: the bottleneck AV observation's size and the
multi-agent rewards without actions (real SUMO where an env is stepped)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flowrun.config.params import EnvParams, NetParams, SumoParams, VehicleParams
from flowrun.envs import BottleneckAccelEnv
from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config
from flowrun.networks import BottleneckNetwork

pytestmark = pytest.mark.sumo

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


def test_bottleneck_accel_obs_ends_with_flows_fake_edge_pair() -> None:
    # Flow's network lists six edges (its GUI-only ``fake_edge`` last): 2 values each, no AV
    vehicles = VehicleParams()
    vehicles.add(veh_id="human", num_vehicles=10)
    params = {"max_accel": 3, "max_decel": 3, "lane_change_duration": 5, "disable_tb": True,
              "disable_ramp_metering": True, "target_velocity": 30,
              "add_rl_if_exit": True}  # fmt: skip
    net_params = NetParams(additional_params={"scaling": 1, "speed_limit": 23})
    net = BottleneckNetwork("bn", vehicles, net_params)
    env = BottleneckAccelEnv(EnvParams(additional_params=params), SumoParams(sim_step=0.5), net)
    try:
        assert env.observation_space.shape == (12,)
        assert (env.observation_space.low.min(), env.observation_space.high.max()) == (0, 1)
        obs, _ = env.reset(seed=0)
        for _ in range(5):
            obs, *_ = env.step(np.zeros(0, dtype=np.float32))
        vk = env.k.vehicle
        v_max = env.k.network.max_speed()
        for i, edge in enumerate(["1", "2", "3", "4", "5"]):
            ids = vk.get_ids_by_edge(edge)
            speed = float(np.mean(vk.get_speed(ids))) / v_max if ids else 0.0
            density = len(ids) / env.k.network.edge_length(edge)
            assert obs[2 * i : 2 * i + 2] == pytest.approx([speed, density], abs=1e-6)
        assert obs[:10].any()  # cars on the road
        assert obs[10:].tolist() == [0.0, 0.0]  # the fake edge: never a car
    finally:
        env.close()


def test_multiagent_rewards_without_actions_are_flows(tmp_path: Path) -> None:
    pytest.importorskip("pettingzoo")
    highway = CONFIGS / "multiagent_merge.yaml"  # the highway's reward class on a merge road
    cases = [
        (CONFIGS / "multiagent_ring.yaml", [], 0.0),
        (CONFIGS / "multiagent_grid.yaml", [], {}),
        (highway, ["env.class=MultiAgentHighwayPOEnv"], {}),
    ]
    for path, overrides, expected in cases:
        env = make_env(load_config(path, ["env.warmup_steps=2", *overrides]))
        try:
            env.reset(seed=0)
            assert env.compute_reward(None) == expected, path.name
            assert type(env.compute_reward(None)) is type(expected)
            # with an actions dict (even an empty one) the reward is computed as before
            if path != highway:
                assert isinstance(env.compute_reward({}, fail=False), float)
        finally:
            env.close()
    ring = make_env(load_config(CONFIGS / "multiagent_ring.yaml", ["env.warmup_steps=2"]))
    try:
        ring.reset(seed=0)
        assert ring.compute_reward({}, fail=False) > 0.0  # 4 mean(v) / 20: cars are moving
    finally:
        ring.close()


def test_grid_cars_closest_to_an_intersection_are_flows() -> None:
    env = make_env(load_config(CONFIGS / "grid0.yaml"))
    try:
        env.reset(seed=0)
        for _ in range(40):
            env.step(np.zeros(env.action_space.shape, dtype=np.float32))
        vk, net = env.k.vehicle, env.k.network
        incoming = env.network.node_mapping[0][1]  # light center0: its four incoming edges
        per_edge = [env.get_closest_to_intersection(e, 3) for e in incoming]
        assert any(len(ids) >= 2 for ids in per_edge)
        for edge, ids in zip(incoming, per_edge, strict=True):
            cars = vk.get_ids_by_edge(edge)
            dist = {v: net.edge_length(edge) - vk.get_position(v) for v in cars}
            assert ids == sorted(cars, key=dist.__getitem__)[:3]  # nearest the node first
            assert env.get_distance_to_intersection(ids) == pytest.approx([dist[v] for v in ids])
            padded = env.get_closest_to_intersection(edge, 5, padding=True)
            assert padded == sorted(cars, key=dist.__getitem__)[:5] + [""] * (5 - len(cars[:5]))
        # a list of edges: the per-edge lists joined (Flow's code pads no list)
        assert env.get_closest_to_intersection(incoming, 3) == [v for ids in per_edge for v in ids]
        assert env.get_closest_to_intersection(incoming, 3, padding=True) == [
            v for ids in per_edge for v in ids
        ]
        assert env.get_distance_to_intersection("nope") == -10.0
        with pytest.raises(ValueError, match="num_closest=0"):
            env.get_closest_to_intersection(incoming, 0)
    finally:
        env.close()


def test_multiagent_step_none_is_flows_step_without_actions() -> None:
    pytest.importorskip("pettingzoo")
    env = make_env(load_config(CONFIGS / "multiagent_ring.yaml", ["env.warmup_steps=2"]))
    try:
        env.reset(seed=0)
        agents = list(env.agents)
        assert agents
        calls: list[object] = []
        original = env._apply_rl_actions
        env._apply_rl_actions = lambda a: calls.append(a) or original(a)  # type: ignore[method-assign]
        obs, rewards, term, trunc, _ = env.step(None)
        assert calls == []  # no RL command: SUMO drives the AVs for the step, as Flow
        assert set(obs) == set(rewards) == set(agents)
        assert rewards == {a: 0.0 for a in agents}  # Flow's compute_reward(None) on the ring
        assert not any(term.values()) and not any(trunc.values())
        _, rewards, *_ = env.step({a: np.zeros(1, dtype=np.float32) for a in agents})
        assert all(r > 0 for r in rewards.values())
    finally:
        env.close()
