"""Flow's mini city and its MinicityRouter: the road as Flow builds it, cars that wander it.

The pure parts (edge table, router draws) run without SUMO; the rest on real SUMO, short and
seeded.
"""

from __future__ import annotations

import itertools
import json
import math
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from flowrun.config.params import (
    ControllerSpec,
    EnvParams,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    VehicleParams,
)
from flowrun.controllers import MinicityRouter, build_controller
from flowrun.controllers.minicity_router import (
    draw_indices,
    follow_edges,
    lane_successors,
    random_routes,
    trigger_index,
)
from flowrun.envs.factory import make_env
from flowrun.envs.ring.accel import ADDITIONAL_ENV_PARAMS, AccelEnv
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config
from flowrun.networks import MiniCityNetwork
from flowrun.networks.minicity import minicity_spec
from flowrun.networks.registry import network_class
from tests.sumo_truth import compare_leaders_with_sumo

CONFIG = Path(__file__).resolve().parent.parent / "configs" / "minicity.yaml"


# --- the road, without SUMO ------------------------------------------------------------------


def test_the_city_has_flows_45_nodes_and_95_edges_with_flows_names() -> None:
    spec = minicity_spec()
    ids = [e.id for e in spec.edges]
    assert len(spec.nodes) == 45 and len(ids) == 95 == len(set(ids))
    assert ids[:8] == ["e_1", "e_2", "e_3", "e_4", "e_5", "e_6", "e_7", "e_8_b"]
    assert {"e_8_u", "e_28_b", "e_29_u", "e_94"} <= set(ids)
    assert not {"e_8", "e_28", "e_29"} & set(ids)
    assert spec.routes["e_42"] == ("e_42",)  # Flow's single-edge routes
    assert all(e.speed == 30.0 for e in spec.edges)


def test_edge_lengths_and_lanes_are_flows() -> None:
    edges = {e.id: e for e in minicity_spec().edges}
    # straight: node distance x 40 (n_i1 (0.65, 2.75) -> n_s1 (0.65, 1.80))
    assert edges["e_2"].length == pytest.approx(0.95 * 40)
    assert edges["e_48"].length == pytest.approx((5.08 - 3.05) * 40)
    # Flow's forced lengths at crowded junctions
    assert (edges["e_1"].length, edges["e_8_b"].length, edges["e_53"].length) == (9.9, 2, 49)
    # curved: a 40-point polyline of an arc of radius 0.43 over 0.50 / 0.43 rad, x 40
    theta, n = 0.50 / 0.43, 39
    chord_sum = 2 * 0.43 * n * math.sin(theta / (2 * n)) * 40
    assert edges["e_10"].length == pytest.approx(chord_sum, rel=1e-9)
    assert edges["e_10"].length < 20.0 and len(edges["e_10"].shape) == 40
    assert (edges["e_5"].lanes, edges["e_7"].lanes, edges["e_14"].lanes) == (1, 2, 1)


def test_edge_starts_lay_flows_edges_end_to_end_in_flows_order() -> None:
    spec = minicity_spec()
    assert spec.edge_starts["e_1"] == 0.0
    assert spec.edge_starts["e_2"] == pytest.approx(9.9)
    assert spec.edge_starts["e_3"] == pytest.approx(9.9 + 38.0)
    last = spec.edges[-1]
    assert spec.edge_starts[last.id] + last.length == pytest.approx(spec.length)


def test_minicity_is_registered_and_takes_no_parameters() -> None:
    assert network_class("minicity") is MiniCityNetwork
    assert network_class("MiniCityNetwork") is MiniCityNetwork
    assert MiniCityNetwork.ADDITIONAL_NET_PARAMS == {}
    from flowrun.scenarios import MiniCityScenario  # Flow < 0.5 path
    from flowrun.scenarios.minicity import ADDITIONAL_NET_PARAMS

    assert MiniCityScenario is MiniCityNetwork and ADDITIONAL_NET_PARAMS == {}
    with pytest.raises(ConfigError, match="takes no parameters") as err:
        MiniCityNetwork.resolve_params({"scaling": 2})
    assert err.value.path == "scaling"


# --- the router's draws, without SUMO --------------------------------------------------------

SUCC = {"a_0": ("b_0", "c_0", "c_1"), "a_1": ("s_0",), "s_0": ("b_0",), "b_0": ("a_0",)}
LENGTHS = {"a": 50.0, "b": 40.0, "c": 30.0, "s": 2.0}


def test_the_next_edge_is_drawn_uniformly_among_the_lanes_links() -> None:
    rng = np.random.default_rng(0)
    routes, ends = random_routes(["a_0"] * 6000, SUCC, LENGTHS, rng, min_edge_length=10.0)
    counts = Counter(r[1] for r in routes)
    assert set(counts) == {"b", "c"} and all(len(r) == 2 for r in routes)
    assert counts["c"] / 6000 == pytest.approx(2 / 3, abs=0.02)  # two of three links
    assert {(r[1], e) for r, e in zip(routes, ends, strict=True)} == {
        ("b", "b_0"),
        ("c", "c_0"),
        ("c", "c_1"),
    }  # the lane each route ends on


def test_a_short_edge_is_followed_by_another_hop_and_zero_lengths_are_flows_one_hop() -> None:
    rng = np.random.default_rng(0)
    assert random_routes(["a_1"], SUCC, LENGTHS, rng, 10.0)[0] == [["a", "s", "b"]]
    assert random_routes(["a_1"], SUCC, LENGTHS, rng, 0.0)[0] == [["a", "s"]]
    assert random_routes(["c_0"], SUCC, LENGTHS, rng)[0] == [["c"]]  # no link: no new edge


def test_hops_go_on_until_they_cover_the_lookahead() -> None:
    rng = np.random.default_rng(0)
    # a_1 -> s (2 m) -> b (40 m) -> a (50 m) -> ...: 92 m covered after three hops
    routes, ends = random_routes(["a_1"], SUCC, LENGTHS, rng, lookahead=60.0)
    assert (routes, ends) == ([["a", "s", "b", "a"]], ["a_0"])
    # what is already ahead counts; no hop is forced when min_hops is 0
    assert random_routes(["a_1"], SUCC, LENGTHS, rng, 0.0, 60.0, [70.0], [0])[0] == [["a"]]
    assert random_routes(["a_1"], SUCC, LENGTHS, rng, 0.0, 60.0, [50.0], [0])[0] == [
        ["a", "s", "b"]
    ]


def test_the_route_is_extended_before_less_than_the_lookahead_is_left() -> None:
    lengths = {"a": 50.0, "b": 40.0, "c": 30.0, "s": 2.0, "d": 20.0}
    # at the end of b 50 m remain (c, d), at the end of c only 20: extend when on c
    assert trigger_index(["a", "b", "c", "d"], lengths, 45.0, 0.0) == 2
    # with no lookahead: on the route's last edge (Flow)
    assert trigger_index(["a", "b", "c", "d"], lengths, 0.0, 0.0) == 3
    # a short edge may be crossed unseen: the next one is the trigger
    assert trigger_index(["a", "s", "b", "c"], lengths, 75.0, 10.0) == 2
    assert trigger_index(["a", "b"], lengths, 500.0, 0.0) == 1


def test_draws_come_from_the_generator_only() -> None:
    def draw(seed: int) -> list[list[str]]:
        return random_routes(["a_0"] * 50, SUCC, LENGTHS, np.random.default_rng(seed), 0, 100)[0]

    assert draw(7) == draw(7) and draw(7) != draw(8)
    picks = draw_indices(np.array([1, 2, 3] * 100), np.random.default_rng(0))
    assert picks.min() == 0 and (picks < np.array([1, 2, 3] * 100)).all()


def test_lane_links_and_forced_paths() -> None:
    links = {"a_0": [("b_0", "", True, True, ":j_0_0"), ("c_1", "", True, True, "")]}
    assert lane_successors(links) == {"a_0": ("b_0", "c_1")}
    assert follow_edges("a_1", ["s", "b"], SUCC) == "b_0"
    assert follow_edges("a_0", ["s"], SUCC) is None


def test_router_parameters_are_checked() -> None:
    router = build_controller("MinicityRouter", {"min_edge_length": 0, "lookahead": 0})
    assert (router.min_edge_length, router.lookahead) == (0.0, 0.0)
    assert (MinicityRouter().lookahead, MinicityRouter().min_edge_length) == (60.0, 10.0)
    with pytest.raises(ConfigError, match="did you mean 'min_edge_length'"):
        build_controller("MinicityRouter", {"min_edge_lenght": 5})
    with pytest.raises(ConfigError, match="min_edge_length must be >= 0"):
        build_controller("MinicityRouter", {"min_edge_length": -1})
    with pytest.raises(ConfigError, match="lookahead must be >= 0"):
        build_controller("MinicityRouter", {"lookahead": -5})
    assert MinicityRouter(veh_id="idm_0", router_params={}).veh_id == "idm_0"  # Flow's call


# --- on SUMO ---------------------------------------------------------------------------------


def city(cars: int = 40, seed: int = 3, dt: float = 0.1) -> AccelEnv:
    """IDM cars with MinicityRouter, placed at random; right of way at junctions."""
    vehicles = VehicleParams()
    vehicles.add(
        "idm",
        acceleration_controller=ControllerSpec("IDM", {}),
        routing_controller=(MinicityRouter, {}),  # Flow's form
        car_following_params=SumoCarFollowingParams(speed_mode="right_of_way", impatience=0),
        lane_change_params=SumoLaneChangeParams(lane_change_mode="no_lc_safe"),
        num_vehicles=cars,
    )
    net = MiniCityNetwork(
        "minicity", vehicles, NetParams(), InitialConfig(spacing="random", min_gap=5)
    )
    env_params = EnvParams(horizon=10**9, additional_params=dict(ADDITIONAL_ENV_PARAMS))
    return AccelEnv(env_params, SumoParams(sim_step=dt, seed=seed), net)


def edge_successors(env: Any) -> dict[str, set[str]]:
    """Every edge's successor edges, as SUMO built them."""
    out: dict[str, set[str]] = {}
    for lane, links in env.k.network.lanes.links.items():
        if not lane.startswith(":"):
            out.setdefault(lane.rpartition("_")[0], set()).update(
                str(link[0]).rpartition("_")[0] for link in links
            )
    return out


@pytest.mark.sumo
def test_sumo_builds_flows_lengths_lanes_and_lane_merges() -> None:
    env = city(cars=5)
    try:
        env.reset(seed=3)
        net = env.k.network
        assert net.edge_length("e_1") == pytest.approx(9.9)
        spec_edges = {e.id: e for e in minicity_spec().edges}
        assert net.edge_length("e_10") == pytest.approx(spec_edges["e_10"].length)
        assert (net.num_lanes("e_13"), net.num_lanes("e_14")) == (2, 1)
        links = net.lanes.links
        assert [str(x[0]) for x in links["e_13_0"]] == ["e_14_0"]
        assert [str(x[0]) for x in links["e_13_1"]] == ["e_14_0"]  # Flow's 2 -> 1 lanes
        succ = edge_successors(env)
        assert len(succ) == 95 and all(succ.values())  # no dead end anywhere
        assert succ["e_37"] == {"e_29_u"} and succ["e_29_u"] == {"e_21"}
    finally:
        env.close()


@pytest.mark.sumo
def test_router_keeps_every_car_driving_on_valid_successors_and_nobody_leaves() -> None:
    env = city(cars=40)
    try:
        env.reset(seed=3)
        vk, v = env.k.vehicle, env.k.vehicle.api.vehicle
        succ = edge_successors(env)
        starts = minicity_spec().edge_starts
        visited: dict[str, set[str]] = {}
        forced_seen = 0
        for _ in range(600):
            _, _, terminated, _, _ = env.step(None)
            assert not terminated
            assert len(vk.get_ids()) == 40 and not vk.get_arrived_ids()
            for vid in vk.get_ids():
                route, index = v.getRoute(vid), v.getRouteIndex(vid)
                ahead = route[index:]
                edge = vk.get_edge(vid)
                if not edge.startswith(":"):
                    assert ahead[0] == edge and len(ahead) >= 2, (vid, edge, ahead)
                    visited.setdefault(vid, set()).add(edge)
                    x = starts[edge] + v.getLanePosition(vid)  # Flow's edge starts
                    assert abs(vk.get_x_by_id(vid) - x) < 1e-6, vid
                for a, b in itertools.pairwise(ahead):
                    assert b in succ[a], (vid, a, b)
                if edge in ("e_37", "e_51"):  # Flow's fixed way on
                    assert ahead[1:3] == ("e_29_u", "e_21"), (vid, ahead)
                    forced_seen += 1
        counts = sorted(len(e) for e in visited.values())  # edges each car drove on
        assert counts[0] >= 2 and counts[len(counts) // 2] >= 10  # they really wander
        assert len(set().union(*visited.values())) > 60
        assert forced_seen > 0
    finally:
        env.close()


@pytest.mark.sumo
def test_leaders_and_headways_equal_sumos_getleader_for_every_car() -> None:
    env = city(cars=40)
    try:
        env.reset(seed=3)
        compared, across_junction = compare_leaders_with_sumo(env, 300)
        assert compared > 3000
        assert across_junction > 1000  # leaders past the lane's end really were exercised
    finally:
        env.close()


@pytest.mark.sumo
def test_flows_example_config_drives_without_collision_in_a_short_run() -> None:
    cfg = load_config(CONFIG, ["env.horizon=120"])
    assert cfg.network.type == "minicity"
    assert [g.num_vehicles for g in cfg.vehicles.groups] == [90, 10]
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        speeds = []
        for _ in range(120):  # 30 s
            _, _, terminated, truncated, _ = env.step(None)
            assert not terminated
            speeds.append(float(np.mean(env.k.vehicle.speed)))
        assert truncated
        assert env.k.simulation.collisions == 0 and env.k.simulation.teleports == 0
        assert len(env.k.vehicle.get_ids()) == 100
        assert np.mean(speeds[60:]) > 2.0  # the cars drive, not a gridlock
    finally:
        env.close()


def roll(seed: int, steps: int = 150) -> tuple[np.ndarray, list[list[str]]]:
    env = city(cars=30, seed=seed)
    try:
        env.reset(seed=seed)
        vk = env.k.vehicle
        pos, edges = [], []
        for _ in range(steps):
            env.step(None)
            pos.append(np.array([vk.get_x_by_id(vid) for vid in vk.get_ids()]))
            edges.append(list(vk.get_edge(vk.get_ids())))
        return np.array(pos), edges
    finally:
        env.close()


@pytest.mark.sumo
def test_same_seed_gives_the_same_trajectories_and_routes() -> None:
    pos_a, edges_a = roll(11)
    pos_b, edges_b = roll(11)
    pos_c, _ = roll(12)
    assert edges_a == edges_b
    np.testing.assert_array_equal(pos_a, pos_b)
    assert not np.array_equal(pos_a, pos_c)


@pytest.mark.sumo
def test_flowrun_baseline_runs_the_minicity_config(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from flowrun.cli.main import app

    out = tmp_path / "runs"
    args = ["baseline", str(CONFIG), "--steps", "20", "--no-record", "--out", str(out)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    (run_dir,) = [p for p in out.glob("minicity/*") if p.is_dir()]
    run = json.loads((run_dir / "metrics.json").read_text())["runs"][0]
    assert run["steps"] == 101  # the state after reset, then 20 env steps of 5 sim steps
    assert (run["collisions"], run["arrived"]) == (0, 0)
