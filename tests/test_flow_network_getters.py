"""Flow's network getters and hooks on flowrun's own networks: ``k.network.get_edge`` on
junction links (with Flow's names), ``rts`` / ``env.available_routes`` as ``(route, prob)``
lists, Flow's default routes, and a ring subclass redefining ``specify_edges`` /
``specify_routes`` (real SUMO where the network is built)."""

from __future__ import annotations

import math
from typing import Any

import pytest

from flowrun.config.params import InitialConfig, NetParams, SumoCarFollowingParams, VehicleParams
from flowrun.errors import ConfigError, CountMismatchError
from flowrun.networks.ring import RingNetwork
from tests.test_open_kernel import on_network


def test_get_edge_finds_junction_links_by_flows_names() -> None:
    env = on_network("figure_eight")
    env.reset(seed=0)
    try:
        net = env.k.network
        # Flow's figure eight: the bottom ring-end link spans [0, 0.28), "bottom" follows
        assert net.get_edge(0.1) == (":bottom", pytest.approx(0.1))
        assert net.get_edge(5.0) == ("bottom", pytest.approx(4.72))
        # the crossing's links keep SUMO's ids, as Flow names them
        centre = net.get_x(":center_1", 0.0)
        assert net.get_edge(centre + 1.0) == (":center_1", pytest.approx(1.0))
        # every non-internal edge is found at its own start
        for edge in net.get_edge_list():
            assert net.get_edge(net.get_x(edge, 0.5))[0] == edge
    finally:
        env.close()


class NoRoutes(RingNetwork):
    """Flow's test network: a ring whose ``specify_routes`` gives nothing."""

    def specify_routes(self, net_params: Any) -> Any:
        return None


class VariableLanes(RingNetwork):
    """A ring whose four edges have 1, 3, 2 and 4 lanes (its own ``specify_edges``)."""

    def specify_edges(self, net_params: Any) -> list[dict[str, Any]]:
        p = net_params.additional_params
        r = p["length"] / (2 * math.pi)
        out = []
        for i, (name, to, lanes) in enumerate(
            [("bottom", "right", 1), ("right", "top", 3), ("top", "left", 2), ("left", "bottom", 4)]
        ):
            a0 = -math.pi / 2 + i * math.pi / 2
            shape = [(r * math.cos(a0 + k * math.pi / 40), r * math.sin(a0 + k * math.pi / 40))
                     for k in range(21)]  # fmt: skip
            out.append({"id": name, "from": name, "to": to, "speed": 30,
                        "length": p["length"] / 4, "numLanes": lanes, "shape": shape})  # fmt: skip
        return out


def ring_of(cls: type[RingNetwork], n: int = 4, **initial: Any) -> RingNetwork:
    vehicles = VehicleParams()
    vehicles.add("human", num_vehicles=n, car_following_params=SumoCarFollowingParams(min_gap=0))
    return cls("r", vehicles, NetParams(additional_params={"length": 230}),
               InitialConfig(**initial))  # fmt: skip


def test_a_ring_without_routes_gets_flows_default_one_edge_routes() -> None:
    spec = ring_of(NoRoutes).spec
    assert spec.routes == {e: (e,) for e in ("bottom", "right", "top", "left")}
    plain = ring_of(RingNetwork).spec
    assert plain.routes["top"] == ("top", "left", "bottom", "right")


def test_rts_and_available_routes_are_route_probability_lists() -> None:
    from flowrun.core.params import EnvParams, SumoParams
    from flowrun.envs import TestEnv

    env = TestEnv(EnvParams(), SumoParams(), ring_of(NoRoutes, n=1))
    try:
        assert env.k.network.rts == {e: [([e], 1.0)] for e in ("bottom", "right", "top", "left")}
        assert env.available_routes == env.k.network.rts
    finally:
        env.close()


def test_a_ring_subclass_with_its_own_edges_places_cars_on_every_lane() -> None:
    from flowrun.core.params import EnvParams, SumoParams
    from flowrun.envs import TestEnv

    net = ring_of(VariableLanes, n=50, lanes_distribution=5)
    assert [e.lanes for e in net.spec.edges] == [1, 3, 2, 4]
    env = TestEnv(EnvParams(), SumoParams(), net)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        ids = vk.get_ids()
        assert len(ids) == 50
        assert {vk.get_lane(v) for v in ids} == {0, 1, 2, 3}
        assert all(vk.get_lane(v) < env.k.network.num_lanes(vk.get_edge(v)) for v in ids)
    finally:
        env.close()


def test_edges_distribution_counts_that_do_not_add_up_are_an_assertion_error_too() -> None:
    net = ring_of(RingNetwork, n=4, edges_distribution={"top": 2, "bottom": 1})
    with pytest.raises(AssertionError) as err:
        net.start_positions(None)  # type: ignore[arg-type]
    assert isinstance(err.value, ConfigError) and isinstance(err.value, CountMismatchError)
    assert "places 3 vehicles" in str(err.value) and "has 4" in str(err.value)


def test_flows_network_attributes_describe_the_road_in_flows_formats() -> None:
    net = ring_of(RingNetwork)
    assert net.routes["top"] == [(["top", "left", "bottom", "right"], 1.0)]
    assert net.edge_starts == [("bottom", 0.0), ("right", 57.5), ("top", 115.0), ("left", 172.5)]
    assert [e["id"] for e in net.edges] == ["bottom", "right", "top", "left"]
    assert {(e["from"], e["to"], e["numLanes"], e["speed"], e["length"]) for e in net.edges} == {
        ("bottom", "right", 1, 30.0, 57.5), ("right", "top", 1, 30.0, 57.5),
        ("top", "left", 1, 30.0, 57.5), ("left", "bottom", 1, 30.0, 57.5)}  # fmt: skip
    assert math.hypot(net.nodes[0]["x"], net.nodes[0]["y"]) == pytest.approx(230 / (2 * math.pi))
    assert net.connections is None and net.internal_edge_starts == []
    assert ring_of(NoRoutes).routes["left"] == [(["left"], 1.0)]
    # a user's network may still set them itself, as Flow's networks do in __init__
    net.edges = [{"id": "mine"}]
    assert net.edges == [{"id": "mine"}]
