"""Flow's ``I210Router``: cars in lanes 3-5 of the I-210's off-ramp edge take that edge's
first route; elsewhere it is the continuous router (a new route drawn at a route's end)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from flowrun.controllers import I210Router
from flowrun.controllers.registry import resolve_controller
from flowrun.controllers.routing import ContinuousRouter
from flowrun.networks.spec import NetworkSpec

KEEP = I210Router.KEEP_EDGE
NAMES = ["up", KEEP, "main", "ramp", ":j_0"]
SPEC = NetworkSpec(
    nodes=(), edges=(), length=0.0, edge_starts={},
    routes={KEEP: (KEEP, "main"), "up": ("up", KEEP, "main"), "main": ("main",)},
    route_choices={KEEP: (((KEEP, "main"), 0.6), ((KEEP, "ramp"), 0.4))},
)  # fmt: skip


def kernel(edge: list[int], end: list[int], lane: list[int]) -> SimpleNamespace:
    return SimpleNamespace(
        edge_names=NAMES, spec=SPEC, edge_index=np.array(edge), route_end=np.array(end),
        lanes=np.array(lane),
    )  # fmt: skip


def test_it_is_flows_continuous_router_by_name() -> None:
    assert resolve_controller("I210Router") is I210Router
    assert issubclass(I210Router, ContinuousRouter)
    assert not I210Router().reroute_mask([0, 0]).any()  # route_vehicles does the routing


def test_far_left_lanes_of_the_ramp_edge_take_its_first_route() -> None:
    # rows: lane 4 on KEEP headed for the ramp; lane 1 on KEEP headed for the ramp;
    # lane 5 on KEEP already headed for main; a car mid-route on "up"
    vk = kernel(edge=[1, 1, 1, 0], end=[3, 3, 2, 2], lane=[4, 1, 5, 0])
    rows, routes = I210Router().route_vehicles(vk, object(), np.arange(4), np.random.default_rng(0))
    assert rows == [0] and routes == [[KEEP, "main"]]


def test_at_a_routes_end_a_new_one_is_drawn_by_the_probabilities() -> None:
    vk = kernel(edge=[1] * 400, end=[1] * 400, lane=[0] * 400)  # on their route's last edge
    rows, routes = I210Router().route_vehicles(
        vk, object(), np.arange(400), np.random.default_rng(7)
    )
    assert len(rows) == 400
    share = sum(r == [KEEP, "main"] for r in routes) / 400
    assert abs(share - 0.6) < 0.07
    none = I210Router().route_vehicles(vk, None, np.arange(400), np.random.default_rng(7))
    assert none == ([], [])  # a closed ring has no lanes table: nothing to route
