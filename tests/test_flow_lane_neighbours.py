"""Flow's lane leaders / followers (``get_lane_leaders``, ``get_lane_headways``, ...): the
pure rule on hand-made positions, and the getters on a real three-edge highway in SUMO."""

from __future__ import annotations

import numpy as np
import pytest

from flowrun.config.params import EnvParams, InitialConfig, NetParams, SumoParams, VehicleParams
from flowrun.controllers import RLController
from flowrun.envs import AccelEnv
from flowrun.envs.ring.accel import ADDITIONAL_ENV_PARAMS
from flowrun.kernel.lane_neighbours import (
    NO_NEIGHBOUR_GAP,
    LaneGraphView,
    lane_neighbours,
)
from flowrun.networks import HighwayNetwork

LENGTH = 5.0


def straight_road(edges: list[str], lanes: int, length: float) -> LaneGraphView:
    """Edges in a row, each ``length`` m with ``lanes`` lanes, lane i leading to lane i."""

    def step(edge: str, lane: int, by: int) -> list[tuple[str, int]]:
        i = edges.index(edge) + by
        return [(edges[i], lane)] if 0 <= i < len(edges) else []

    return LaneGraphView(
        lambda e: lanes,
        lambda e, lane: step(e, lane, 1),
        lambda e, lane: step(e, lane, -1),
        lambda e: length,
        len(edges),
    )


def neighbours(cars: list[tuple[str, int, float]], me: int, graph: LaneGraphView) -> object:
    edges = [c[0] for c in cars]
    lanes = np.array([c[1] for c in cars])
    pos = np.array([c[2] for c in cars])
    return lane_neighbours(me, edges, lanes, pos, np.full(len(cars), LENGTH), graph)


def test_a_car_level_with_this_one_on_another_lane_is_its_leader_at_minus_its_length() -> None:
    graph = straight_road(["a"], 3, 100.0)
    # car 0 (lane 0, 20 m), car 1 level on lane 1, car 2 behind on lane 2, car 3 ahead on lane 0
    got = neighbours([("a", 0, 20.0), ("a", 1, 20.0), ("a", 2, 10.0), ("a", 0, 40.0)], 0, graph)
    assert got.leaders == [3, 1, -1]
    assert got.headways == [40.0 - 20.0 - LENGTH, -LENGTH, NO_NEIGHBOUR_GAP]
    assert got.followers == [-1, -1, 2]
    assert got.tailways == [NO_NEIGHBOUR_GAP, NO_NEIGHBOUR_GAP, 20.0 - 10.0 - LENGTH]


def test_the_search_goes_on_to_the_next_and_previous_edges_adding_their_lengths() -> None:
    graph = straight_road(["e0", "e1", "e2"], 2, 30.0)
    cars = [("e1", 0, 10.0), ("e2", 1, 4.0), ("e0", 0, 25.0)]
    got = neighbours(cars, 0, graph)
    # ahead on lane 1: 30 m of e1 passed, the leader 4 m into e2
    assert got.leaders == [-1, 1]
    assert got.headways == [NO_NEIGHBOUR_GAP, pytest.approx(4.0 - 10.0 + 30.0 - LENGTH)]
    # behind on lane 0: e0 entered (its 30 m), the follower 25 m into it
    assert got.followers == [2, -1]
    assert got.tailways == [pytest.approx(10.0 - 25.0 + 30.0 - LENGTH), NO_NEIGHBOUR_GAP]


def test_on_its_own_lane_the_car_itself_is_skipped_and_a_road_end_stops_the_search() -> None:
    graph = straight_road(["only"], 1, 50.0)
    got = neighbours([("only", 0, 10.0), ("only", 0, 30.0)], 1, graph)
    assert got.leaders == [-1] and got.headways == [NO_NEIGHBOUR_GAP]
    assert got.followers == [0] and got.tailways == [30.0 - 10.0 - LENGTH]


def test_highway_lane_leaders_span_edges_in_sumo() -> None:
    """Flow's own case: three cars on three edges of a 3-lane highway, each on its lane."""
    net = NetParams(additional_params={
        "length": 100, "lanes": 3, "speed_limit": 30, "num_edges": 3,
        "use_ghost_edge": False, "ghost_speed_limit": 25, "boundary_cell_length": 300})  # fmt: skip
    vehicles = VehicleParams()
    vehicles.add("test", acceleration_controller=(RLController, {}), num_vehicles=3,
                 initial_speed=1.0)  # fmt: skip
    initial = InitialConfig(spacing="custom", additional_params={
        "start_positions": [("highway_1", 50 - 100 / 3), ("highway_2", 75 - 200 / 3),
                            ("highway_0", 25)],
        "start_lanes": [1, 2, 0]})  # fmt: skip
    network = HighwayNetwork("lanes", vehicles, net, initial)
    env = AccelEnv(EnvParams(additional_params=ADDITIONAL_ENV_PARAMS),
                   SumoParams(sim_step=0.1), network)  # fmt: skip
    env.reset(seed=0)
    try:
        vk, nk = env.k.vehicle, env.k.network
        assert vk.get_lane_leaders("test_0") == ["", "", "test_1"]
        assert vk.get_lane_followers("test_0") == ["test_2", "", ""]
        # the gaps add the lengths of every edge passed, junction links included
        ahead = [nk.edge_length("highway_1")]
        edge, lane = "highway_1", 2
        while edge != "highway_2":
            edge, lane = nk.next_edge(edge, lane)[0]
            if edge != "highway_2":
                ahead.append(nk.edge_length(edge))
        expected = vk.get_position("test_1") - vk.get_position("test_0") + sum(ahead) - 5.0
        heads = vk.get_lane_headways("test_0")
        assert heads[:2] == [NO_NEIGHBOUR_GAP, NO_NEIGHBOUR_GAP]
        assert heads[2] == pytest.approx(expected)
        assert 20.0 < heads[2] < 21.0
        assert vk.get_lane_leaders_speed("test_0") == [0.0, 0.0, pytest.approx(1.0)]
        assert vk.get_lane_tailways("test_0")[1:] == [NO_NEIGHBOUR_GAP, NO_NEIGHBOUR_GAP]
    finally:
        env.close()
