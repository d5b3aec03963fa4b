"""Initial placement on open and multi-edge networks (Flow's ``InitialConfig`` semantics)."""

from __future__ import annotations

import itertools
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest

from flowrun.config.params import InitialConfig, NetParams, VehicleParams
from flowrun.errors import ConfigError
from flowrun.networks import FigureEightNetwork, HighwayNetwork, MergeNetwork
from flowrun.networks.base import Network, StartPositions
from flowrun.networks.build import build_network

UNIT = 5.0 + 2.5  # default vehicle length + SUMO minGap, m


def network(
    cls: type[Network], n: int, params: dict[str, object] | None = None, **initial: object
) -> Network:
    vehicles = VehicleParams()
    if n:
        vehicles.add("human", num_vehicles=n)
    net = NetParams(additional_params=dict(params or {}))
    return cls("test", vehicles, net, InitialConfig(**initial))  # type: ignore[arg-type]


def place(net: Network, seed: int = 0) -> StartPositions:
    return net.start_positions(np.random.default_rng(seed))


def check_no_overlap(net: Network, start: StartPositions, unit: float = UNIT) -> None:
    """Cars on edges (not junctions), on existing lanes, fronts >= ``unit`` apart per lane,
    and at least ``unit`` between cars across each junction a route drives through."""
    edges = {e.id: e for e in net.spec.edges}
    lanes: dict[tuple[str, int], list[float]] = defaultdict(list)
    for edge, pos, lane in zip(start.edges, start.lane_pos, start.lanes, strict=True):
        assert not edge.startswith(":")
        assert 0 <= lane < edges[edge].lanes
        assert 0.0 <= pos <= edges[edge].length + 1e-9
        lanes[(edge, lane)].append(pos)
    for pos_list in lanes.values():
        assert np.all(np.diff(np.sort(pos_list)) >= unit - 1e-9)
    pairs = {p for r in net.spec.routes.values() for p in itertools.pairwise(r)}
    for (a, b), lane in ((p, k) for p in pairs for k in range(8)):
        if (a, lane) in lanes and (b, lane) in lanes:
            gap = edges[a].length - max(lanes[(a, lane)]) + min(lanes[(b, lane)])
            assert gap >= unit - 1e-9, f"{a} -> {b} lane {lane}: {gap}"
    for (edge, _), pos_list in lanes.items():  # a car whose back hangs over the edge start
        if min(pos_list) < unit:  # must come from the edge before it in a route
            assert any(b == edge for _, b in pairs)


def test_uniform_placement_on_the_figure_eight_spreads_cars_over_the_loop() -> None:
    net = network(FigureEightNetwork, 14)
    start = place(net)
    assert len(start.edges) == 14
    assert set(start.edges) == {"bottom", "top", "upper_ring", "right", "left", "lower_ring"}
    check_no_overlap(net, start)
    # in driving order: positions along the loop increase with the vehicle index
    x = [net.spec.edge_starts[e] + p for e, p in zip(start.edges, start.lane_pos, strict=True)]
    assert np.all(np.diff(x) > 0)
    assert start.lanes == [0] * 14


def test_merge_with_no_vehicles_places_none() -> None:
    assert place(network(MergeNetwork, 0)) == StartPositions([], [], [])


@pytest.mark.parametrize("spacing", ["uniform", "random"])
def test_merge_placement_keeps_gaps_across_the_merge(spacing: str) -> None:
    for seed in range(10):
        net = network(MergeNetwork, 40, spacing=spacing)
        start = place(net, seed)
        assert len(start.edges) == 40
        check_no_overlap(net, start)


def test_highway_rows_fill_all_lanes_side_by_side() -> None:
    net = network(HighwayNetwork, 12, {"length": 300, "num_edges": 3})
    start = place(net)
    assert start.lanes == [0, 1, 2, 3] * 3
    assert len(set(zip(start.edges, start.lane_pos, strict=True))) == 3  # 3 rows of 4
    check_no_overlap(net, start)


def test_lanes_distribution_limits_the_lanes_used() -> None:
    start = place(network(HighwayNetwork, 10, lanes_distribution=2))
    assert set(start.lanes) == {0, 1}
    start = place(network(HighwayNetwork, 10, lanes_distribution=0.5))  # below 1 counts as 1
    assert set(start.lanes) == {0}


def test_ghost_edge_gets_no_cars_by_default() -> None:
    net = network(HighwayNetwork, 30, {"use_ghost_edge": True, "num_edges": 2}, spacing="random")
    assert "highway_end" not in place(net).edges


def test_edges_distribution_list_and_dict_are_respected() -> None:
    net = network(MergeNetwork, 8, edges_distribution=["bottom", "inflow_merge"])
    start = place(net)
    assert set(start.edges) == {"bottom", "inflow_merge"}
    check_no_overlap(net, start)
    net = network(MergeNetwork, 8, edges_distribution={"left": 5, "bottom": 3})
    start = place(net)
    assert start.edges == ["left"] * 5 + ["bottom"] * 3
    check_no_overlap(net, start)


def test_edges_distribution_errors_name_the_problem() -> None:
    with pytest.raises(ConfigError, match="did you mean 'bottom'") as err:
        place(network(MergeNetwork, 4, edges_distribution=["botom"]))
    assert err.value.path == "edges_distribution"
    with pytest.raises(ConfigError, match="places 3 vehicles but the vehicles section has 4"):
        place(network(MergeNetwork, 4, edges_distribution={"left": 3}))
    with pytest.raises(ConfigError, match=r"vehicles need 7\.5 m each"):
        place(network(MergeNetwork, 30, edges_distribution=["bottom"]))


def test_bunching_leaves_road_empty_and_negative_bunching_counts_as_zero() -> None:
    base = place(network(HighwayNetwork, 10, {"lanes": 1}))
    bunched = place(network(HighwayNetwork, 10, {"lanes": 1}, bunching=500.0))
    assert max(bunched.lane_pos) < 500.0 < max(base.lane_pos)
    negative = place(network(HighwayNetwork, 10, {"lanes": 1}, bunching=-50.0))
    assert negative == base


def test_unknown_spacing_is_refused() -> None:
    with pytest.raises(ConfigError, match="unknown spacing 'even'") as err:
        place(network(MergeNetwork, 4, spacing="even"))
    assert err.value.path == "spacing"


def test_custom_spacing_needs_the_networks_own_generator() -> None:
    with pytest.raises(ConfigError, match=r"MergeNetwork\.gen_custom_start_pos") as err:
        place(network(MergeNetwork, 4, spacing="custom"))
    assert err.value.path == "spacing"


def test_x0_shifts_the_first_car_and_wraps() -> None:
    net = network(HighwayNetwork, 4, {"lanes": 1, "length": 400}, x0=100.0)
    start = place(net)
    assert start.lane_pos[0] == pytest.approx(100.0 + UNIT)
    check_no_overlap(net, start)


def test_random_and_perturbed_placements_are_seeded() -> None:
    for spacing, perturbation in (("random", 0.0), ("uniform", 2.0)):
        net = network(FigureEightNetwork, 14, spacing=spacing, perturbation=perturbation)
        a, b, c = place(net, 3), place(net, 3), place(net, 4)
        assert a == b and a != c


def test_min_gap_and_shuffle() -> None:
    net = network(MergeNetwork, 12, spacing="random", min_gap=3.0)
    for seed in range(10):
        check_no_overlap(net, place(net, seed), UNIT + 3.0)
    vehicles = VehicleParams()
    vehicles.add("a", num_vehicles=6)
    vehicles.add("b", num_vehicles=6)
    plain = HighwayNetwork("t", vehicles, NetParams(), InitialConfig())
    shuffled = HighwayNetwork("t", vehicles, NetParams(), InitialConfig(shuffle=True))
    p, s = place(plain, 1), place(shuffled, 1)
    assert sorted(zip(p.edges, p.lane_pos, p.lanes, strict=True)) == sorted(
        zip(s.edges, s.lane_pos, s.lanes, strict=True)
    )
    assert p != s


@pytest.mark.parametrize("cls", [FigureEightNetwork, MergeNetwork, HighwayNetwork])
def test_sumo_inserts_every_placed_car(tmp_path: Path, cls: type[Network]) -> None:
    libsumo = pytest.importorskip("libsumo")
    net = network(cls, 14, {"num_edges": 2} if cls is HighwayNetwork else None)
    start = place(net)
    net_file = build_network(net.spec, tmp_path, cls.network_type)
    rows = ['<routes><vType id="car" length="5" minGap="2.5"/>']
    for start_edge, route in net.spec.routes.items():
        rows.append(f'<route id="r_{start_edge}" edges="{" ".join(route)}"/>')
    for i, (e, p, k) in enumerate(zip(start.edges, start.lane_pos, start.lanes, strict=True)):
        rows.append(f'<vehicle id="v{i}" type="car" route="r_{e}" depart="0" '
                    f'departPos="{p}" departLane="{k}" departSpeed="0"/>')  # fmt: skip
    rou = tmp_path / "cars.rou.xml"
    rou.write_text("\n".join([*rows, "</routes>"]))
    libsumo.start(["sumo", "-n", str(net_file), "-r", str(rou), "--no-step-log", "true",
                   "--no-warnings", "true", "--collision.action", "warn"])  # fmt: skip
    try:
        libsumo.simulationStep()
        assert libsumo.vehicle.getIDCount() == 14
        assert libsumo.simulation.getCollidingVehiclesNumber() == 0
        for i, (e, p) in enumerate(zip(start.edges, start.lane_pos, strict=True)):
            assert libsumo.vehicle.getRoadID(f"v{i}") == e
            assert libsumo.vehicle.getLanePosition(f"v{i}") == pytest.approx(p, abs=1e-6)
    finally:
        libsumo.close()
