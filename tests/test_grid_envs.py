"""The traffic-light grid network and Flow's signal-control envs (grid0/grid1).

Pure parts (switch timers, edge numbers, spaces) run without SUMO; the SUMO tests are short
and seeded and read every light back from SUMO.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from flowrun.config.params import EnvParams, NetParams, SumoParams, VehicleParams
from flowrun.envs.factory import make_env
from flowrun.envs.signals import SwitchTimers, discrete_mask, edge_number, phase_state
from flowrun.envs.traffic_light_grid import (
    TrafficLightGridBenchmarkEnv,
    TrafficLightGridEnv,
    TrafficLightGridPOEnv,
)
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config
from flowrun.networks.registry import network_class
from flowrun.networks.traffic_light_grid import TrafficLightGridNetwork

LENGTHS = {"inner_length": 100, "short_length": 100, "long_length": 100}
CONFIGS = Path(__file__).resolve().parent.parent / "configs"


def grid(rows: int = 3, cols: int = 3, **extra: object) -> TrafficLightGridNetwork:
    params = {"grid_array": {"row_num": rows, "col_num": cols, "inner_length": 300,
                             "short_length": 300, "long_length": 100}, **extra}  # fmt: skip
    return TrafficLightGridNetwork("g", VehicleParams(), NetParams(additional_params=params))


# ---------------------------------------------------------------- network, no SUMO
def test_grid_has_flows_edge_names_lengths_and_straight_routes() -> None:
    spec = grid().spec
    edges = {e.id: e for e in spec.edges}
    assert len(edges) == 48  # 3x3: 2 * (3 rows * 4 + 3 cols * 4)
    assert edges["bot0_0"].length == 300 and edges["bot0_3"].length == 100
    assert edges["bot0_1"].from_node == "center0" and edges["bot0_1"].to_node == "center1"
    assert edges["left3_2"].to_node == "center8" and edges["right3_2"].from_node == "center8"
    assert spec.routes["bot1_0"] == ("bot1_0", "bot1_1", "bot1_2", "bot1_3")
    assert spec.routes["left3_0"] == ("left3_0", "left2_0", "left1_0", "left0_0")
    assert spec.routes["top0_3"] == ("top0_3", "top0_2", "top0_1", "top0_0")
    lights = [n.id for n in spec.nodes if n.type == "traffic_light"]
    assert lights == [f"center{i}" for i in range(9)]


def test_speed_limit_per_direction_and_lanes() -> None:
    spec = grid(speed_limit={"horizontal": 20, "vertical": 10}, vertical_lanes=2).spec
    edges = {e.id: e for e in spec.edges}
    assert (edges["bot0_1"].speed, edges["bot0_1"].lanes) == (20.0, 1)
    assert (edges["right1_0"].speed, edges["right1_0"].lanes) == (10.0, 2)


def test_node_mapping_lists_the_four_incoming_edges_sorted_by_name() -> None:
    mapping = dict(grid().node_mapping)
    assert list(dict(grid().node_mapping)) == sorted(f"center{i}" for i in range(9))
    assert mapping["center4"] == ["bot1_1", "right1_1", "top1_2", "left2_1"]
    spec = grid().spec
    to = {e.id: e.to_node for e in spec.edges}
    assert all(to[e] == node for node, edges in mapping.items() for e in edges)


@pytest.mark.parametrize(
    ("params", "path"),
    [
        ({"grid_array": {"row_num": 2}}, "grid_array.inner_length"),
        (
            {"grid_array": {"row_num": 0, "inner_length": 1, "short_length": 1, "long_length": 1}},
            "grid_array.row_num",
        ),
        ({"grid_array": {"rows": 2}}, "grid_array.rows"),
        ({"grid_array": LENGTHS, "speed_limit": {"horizontal": 3}}, "speed_limit"),
    ],
)
def test_bad_grid_parameters_name_the_key(params: dict[str, object], path: str) -> None:
    with pytest.raises(ConfigError) as err:
        TrafficLightGridNetwork.resolve_params(params)
    assert err.value.path == path


def test_registry_and_flows_old_names() -> None:
    from flowrun.envs.green_wave_env import PO_TrafficLightGridEnv
    from flowrun.scenarios.grid import SimpleGridScenario

    assert network_class("traffic_light_grid") is TrafficLightGridNetwork
    assert network_class("TrafficLightGridNetwork") is SimpleGridScenario
    assert PO_TrafficLightGridEnv is TrafficLightGridPOEnv


# ---------------------------------------------------------------- pure env parts
def test_switch_goes_through_yellow_for_switch_time_and_ignores_requests_meanwhile() -> None:
    timers = SwitchTimers(1, switch_time=3.0, dt=1.0)
    assert timers.step(np.array([True])) == [(0, 0, True)]  # vertical green -> yellow
    assert timers.step(np.array([True])) == []  # yellow: request ignored (1 s)
    assert timers.step(np.array([True])) == []  # 2 s
    assert timers.step(np.array([True])) == [(0, 1, False)]  # 3 s: horizontal green
    assert timers.step(np.array([True])) == [(0, 1, True)]  # next switch 4 s after the first
    assert list(timers.features()) == [0.0, 0.0, 1.0]


def test_timers_of_several_lights_step_independently_and_pack_their_features() -> None:
    timers = SwitchTimers(3, switch_time=2.0, dt=0.5)
    assert timers.step(np.array([True, False, True])) == [(0, 0, True), (2, 0, True)]
    assert timers.step(np.array([False, True, False])) == [(1, 0, True)]
    for _ in range(2):
        assert timers.step(np.zeros(3, dtype=bool)) == []
    assert timers.step(np.zeros(3, dtype=bool)) == [(0, 1, False), (2, 1, False)]  # 2 s
    assert timers.last_change.tolist() == [2.0, 1.5, 2.0]
    # features() and the packed array are the three per-light arrays, concatenated
    expected = [2.0, 1.5, 2.0, 1.0, 1.0, 1.0, 0.0, 1.0, 0.0]
    assert timers.features().tolist() == timers.packed.tolist() == expected
    timers.reset()
    assert timers.packed.tolist() == [0.0] * 9 and timers.direction.tolist() == [0.0] * 3


def test_phase_states_match_flows_for_four_links() -> None:
    vertical = [True, False, True, False]  # SUMO's order: from above, right, below, left
    assert phase_state(vertical, 0, False) == "GrGr"
    assert phase_state(vertical, 0, True) == "yryr"
    assert phase_state(vertical, 1, False) == "rGrG"
    assert phase_state(vertical, 1, True) == "ryry"


def test_discrete_action_bits_and_edge_numbers() -> None:
    assert discrete_mask(5, 4).tolist() == [False, True, False, True]
    numbers = {edge_number(e.id, 3, 3) for e in grid().spec.edges}
    assert numbers == set(range(1, 49))  # every edge its own number, as Flow's _convert_edge
    assert edge_number("", 3, 3) == 0
    assert edge_number(":center4_0_0", 3, 3) == 48 + 4 + 1  # after the 48 edges


def make(env_cls: type, **params: object) -> TrafficLightGridEnv:
    vehicles = VehicleParams()
    net = grid()
    additional = {"switch_time": 3, "tl_type": "controlled", "discrete": False,
                  "num_observed": 2, "target_velocity": 50, **params}  # fmt: skip
    return env_cls(EnvParams(horizon=20, additional_params=additional),
                   SumoParams(sim_step=1.0), TrafficLightGridNetwork(
                       "g", vehicles, net.net_params))  # fmt: skip


def test_flows_private_grid_helpers_number_edges_and_find_neighbour_lights() -> None:
    env = make(TrafficLightGridEnv)  # 3 x 3, SUMO not started
    try:
        # Flow's numbering: per row of lights, its vertical edges then its horizontal ones
        assert env._split_edge("left0_0") == 1 and env._split_edge("right0_0") == 2
        assert env._split_edge("bot0_0") == 7 and env._split_edge("top0_0") == 8
        assert env._split_edge(":center4") == 48 + 4 + 1 and env._split_edge("") == 0
        assert env._convert_edge(["top0_0", "left0_0", ""]) == [8, 1, 0]
        # lights numbered row by row from the bottom left; -1 past the grid's edge
        assert [env._get_relative_node("center4", s) for s in ("top", "bottom", "left",
                                                               "right")] == [7, 1, 3, 5]
        assert env._get_relative_node("center2", "right") == -1
        with pytest.raises(NotImplementedError):
            env._get_relative_node("center0", "up")
    finally:
        env.close()


def test_observation_sizes_are_flows_339_and_915() -> None:
    assert make(TrafficLightGridBenchmarkEnv).observation_space.shape == (339,)
    cfg = load_config(CONFIGS / "grid1.yaml")
    env = make_env(cfg)
    assert env.observation_space.shape == (915,)
    assert env.action_space.shape == (25,)
    env.close()


def test_rl_env_on_a_network_without_lights_is_one_clear_error() -> None:
    vehicles = VehicleParams()
    params = {"grid_array": {"row_num": 1, "col_num": 1, **LENGTHS}, "traffic_lights": False}
    net = TrafficLightGridNetwork("g", vehicles, NetParams(additional_params=params))
    with pytest.raises(ConfigError, match="has none"):
        TrafficLightGridEnv(EnvParams(additional_params={"switch_time": 2, "tl_type": "x",
                                                         "discrete": False}),
                            SumoParams(), net)  # fmt: skip


# ---------------------------------------------------------------- SUMO
@pytest.mark.sumo
@pytest.mark.parametrize("name", ["grid0"])
def test_grid_config_env_passes_check_env(name: str) -> None:
    env = make_env(load_config(CONFIGS / f"{name}.yaml"))
    try:
        check_env(env, skip_render_check=True)
    finally:
        env.close()


@pytest.mark.sumo
@pytest.mark.parametrize("discrete", [False, True])
def test_full_observation_env_passes_check_env(discrete: bool) -> None:
    env = make(TrafficLightGridEnv, discrete=discrete)
    try:
        check_env(env, skip_render_check=True)
    finally:
        env.close()


@pytest.mark.sumo
def test_rl_cannot_switch_faster_than_switch_time_and_green_to_red_passes_yellow() -> None:
    env = make_env(load_config(CONFIGS / "grid0.yaml"))
    rng = np.random.default_rng(3)
    try:
        env.reset(seed=3)
        tk = env.k.traffic_light
        api = env.k.vehicle.api.trafficlight
        history: dict[str, list[str]] = {t: [tk.get_state(t)] for t in tk.get_ids()}
        for _ in range(150):
            env.step(rng.uniform(-1, 1, 9).astype(np.float32))
            for t in tk.get_ids():
                assert tk.get_state(t) == api.getRedYellowGreenState(t)
                history[t].append(tk.get_state(t))
        switches = 0
        for states in history.values():
            for a, b in itertools.pairwise(states):
                for x, y in zip(a, b, strict=True):
                    assert not (x == "G" and y == "r"), (a, b)  # green never straight to red
            # a yellow lasts switch_time (3 s = 3 steps) and greens last >= 1 step
            runs = [(s, len(list(g))) for s, g in itertools.groupby(states)]
            for s, length in runs[1:-1]:
                if "y" in s:
                    assert length == 3
                    switches += 1
            starts = [i for i, (a, b) in enumerate(itertools.pairwise(states))
                      if "y" not in a and "y" in b]  # fmt: skip
            assert all(b - a >= 4 for a, b in itertools.pairwise(starts))
        assert switches > 50
    finally:
        env.close()


@pytest.mark.sumo
def test_po_edge_density_and_speed_equal_the_kernel_getters() -> None:
    env = make_env(load_config(CONFIGS / "grid0.yaml"))
    try:
        env.reset(seed=0)
        for _ in range(60):
            obs, *_ = env.step(np.ones(9, dtype=np.float32))
        assert isinstance(env, TrafficLightGridPOEnv)
        vk, net = env.k.vehicle, env.k.network
        n_edges = len(env.edge_list)
        start = 3 * 4 * env.num_observed * env.num_traffic_lights
        density, speed = obs[start : start + n_edges], obs[start + n_edges : start + 2 * n_edges]
        seen = 0
        for i, edge in enumerate(env.edge_list):
            ids = vk.get_ids_by_edge(edge)
            want = 5.0 * len(ids) / net.edge_length(edge)
            assert density[i] == pytest.approx(want, rel=1e-6)
            mean = float(np.mean(vk.get_speed(ids))) / net.max_speed() if ids else 0.0
            assert speed[i] == pytest.approx(mean, rel=1e-5, abs=1e-7)
            seen += len(ids)
        assert seen > 20
    finally:
        env.close()


def test_full_env_puts_cars_that_reach_an_exit_back_at_their_entry_as_flow() -> None:
    from flowrun.config.params import InitialConfig
    from flowrun.controllers import GridRouter, SimCarFollowingController
    from flowrun.envs.traffic_light_grid import reentry_edges

    assert reentry_edges(2, 3)["bot1_3"] == "bot1_0"
    assert reentry_edges(2, 3)["left0_2"] == "left2_2"
    vehicles = VehicleParams()
    vehicles.add("human", acceleration_controller=(SimCarFollowingController, {}),
                 routing_controller=(GridRouter, {}), num_vehicles=16)  # fmt: skip
    cars = {f"cars_{side}": 2 for side in ("top", "bot", "left", "right")}
    params = {"grid_array": {"row_num": 2, "col_num": 2, **cars, **LENGTHS}, "speed_limit": 20}
    net = TrafficLightGridNetwork(
        "g", vehicles, NetParams(additional_params=params), InitialConfig(spacing="custom")
    )
    extra = {"switch_time": 2.0, "tl_type": "actuated", "discrete": False}
    env = TrafficLightGridEnv(
        EnvParams(horizon=1000, additional_params=extra), SumoParams(sim_step=0.5, seed=0), net
    )
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        reentry = reentry_edges(2, 2)
        came_back, last = 0, dict(zip(vk.get_ids(), vk.edges, strict=True))
        for _ in range(300):
            env.step(np.zeros(4, np.float32))
            assert vk.num_vehicles == 16 == vk.api.vehicle.getIDCount()
            for vid, edge in zip(vk.get_ids(), vk.edges, strict=True):
                came_back += edge == reentry.get(last.get(vid, ""))
                last[vid] = edge
        assert came_back >= 16  # every car went round at least once on average
        assert sorted(vk.get_ids()) == sorted(f"human_{i}" for i in range(16))
    finally:
        env.close()


def test_po_env_marks_its_observed_cars_and_rewards_read_every_speed() -> None:
    from flowrun.core import rewards

    env = make_env(load_config(CONFIGS / "grid0.yaml", ["env.horizon=60"]))
    try:
        env.reset(seed=0)
        for _ in range(40):
            env.step(np.zeros(9, np.float32))
        vk = env.k.vehicle
        observed = [v for v in env.observed_ids if v in vk.table]  # type: ignore[attr-defined]
        assert observed and set(observed) <= set(vk.get_observed_ids())
        speeds = np.array(vk.get_speed(vk.get_ids()))
        assert rewards.penalize_standstill(env) == -np.count_nonzero(speeds == 0)
        v_top = max(env.k.network.speed_limit(e) for e in env.k.network.get_edge_list())
        delay = env.sim_step * np.sum((v_top - speeds) / v_top) / len(speeds)
        assert rewards.min_delay_unscaled(env) == pytest.approx(delay, rel=1e-6)
    finally:
        env.close()
