"""Flow's bottleneck: a scalable model of the Bay Bridge toll plaza's two-stage lane drop.

Five straight edges along the x axis, named as in Flow: ``1`` (100 m) -> ``2`` (310 m) ->
``3`` (140 m), each ``4 * scaling`` lanes wide, then ``4`` (280 m, ``2 * scaling`` lanes) and
``5`` (155 m, ``scaling`` lanes), their lanes centred on the road's line (Flow's
``spreadType: center``). Nodes ``1`` .. ``6`` sit at Flow's x = 0, 100, 410, 550, 830,
985 m; ``4`` and ``5`` are SUMO *zipper* junctions (radius 20 m), where lane ``i`` of the wider
edge feeds lane ``floor(i / 2)`` of the narrower one, so two lanes merge alternately into
one. Cars enter on ``1`` from inflows; every start edge routes to the end of ``5``. A node
named in the traffic lights (Flow's toll booth at ``2``, ramp meter at ``3``) becomes one.

Positions along the network (``get_x_by_id``) run through the junctions: each edge starts
where the one before it ends plus the junction's internal link (measured on SUMO 1.28), so
they grow monotonically along the road. (Flow lists 0, 100, 405, 425, 580 m, which overlap
edge ``3`` and ``4``; flowrun's are the distances a car actually drives.)
"""

from __future__ import annotations

from typing import Any, ClassVar

from flowrun.networks.base import Network
from flowrun.networks.spec import Connection, Edge, NetworkSpec, Node

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # factor multiplying the number of lanes (4s -> 2s -> 1s)
    "scaling": 1,
    # speed limit of all edges, m/s
    "speed_limit": 23,
}

KINDS = {"scaling": "count", "speed_limit": "positive"}

#: Flow's edges: id, start node, end node, length (m), lanes per unit of ``scaling``
EDGES: tuple[tuple[str, str, str, float, int], ...] = (
    ("1", "1", "2", 100.0, 4),
    ("2", "2", "3", 310.0, 4),
    ("3", "3", "4", 140.0, 4),
    ("4", "4", "5", 280.0, 2),
    ("5", "5", "6", 155.0, 1),
)
#: Flow's nodes: id, x (m), SUMO junction type, radius (m)
NODES: tuple[tuple[str, float, str, float | None], ...] = (
    ("1", 0.0, "priority", None),
    ("2", 100.0, "priority", None),
    ("3", 410.0, "priority", None),
    ("4", 550.0, "zipper", 20.0),
    ("5", 830.0, "zipper", 20.0),
    ("6", 985.0, "priority", None),
)
MAIN_ROUTE = tuple(e[0] for e in EDGES)
#: length of the link through a plain node between two equal edges, m (SUMO 1.28)
PLAIN_LINK = 0.1
#: length of the links through a zipper node by the number of lanes that merge there, m
#: (SUMO 1.28 builds every lane's link through it this long; measured, see the tests)
ZIPPER_LINKS: dict[int, float] = {2: 40.031987, 4: 40.063898, 6: 40.140779, 8: 40.231766,
                                  10: 40.374476, 12: 40.517061, 16: 40.903515,
                                  20: 41.388543}  # fmt: skip


def zipper_link(lanes_in: int) -> float:
    """Length of the links through a zipper node that ``lanes_in`` lanes enter, m: measured
    up to 20 lanes (scaling 5), beyond that an upper bound (positions then skip a little,
    never overlap)."""
    return ZIPPER_LINKS.get(lanes_in, 40.0 + 0.02 * lanes_in**2)


def bottleneck_edge_starts(links: tuple[float, float, float, float]) -> dict[str, float]:
    """Start of each edge along the road: the edges before it plus the links between, m."""
    starts, x = {}, 0.0
    for (eid, *_, length, _), link in zip(EDGES, (*links, 0.0), strict=True):
        starts[eid] = x
        x += length + link
    return starts


def bottleneck_spec(
    scaling: int, speed_limit: float, lights: frozenset[str] = frozenset()
) -> NetworkSpec:
    """Nodes, edges, zipper connections and routes of the bottleneck (module docstring);
    the nodes in ``lights`` are traffic lights (Flow's toll booth ``2``, ramp meter ``3``)."""
    nodes = tuple(
        Node(i, x, 0.0, "traffic_light" if i in lights else kind, radius)
        for i, x, kind, radius in NODES
    )
    edges = tuple(
        Edge(eid, a, b, length, lanes * scaling, speed_limit, spread_type="center")
        for eid, a, b, length, lanes in EDGES
    )
    connections = tuple(
        Connection(a.id, b.id, i, i // 2)
        for a, b in ((edges[2], edges[3]), (edges[3], edges[4]))
        for i in range(a.lanes)
    )
    # between equal edges netconvert links lane i to lane i
    connections += tuple(
        Connection(a.id, b.id, i, i)
        for a, b in ((edges[0], edges[1]), (edges[1], edges[2]))
        for i in range(a.lanes)
    )
    zip4, zip5 = zipper_link(4 * scaling), zipper_link(2 * scaling)
    routes = {e.id: MAIN_ROUTE[i:] for i, e in enumerate(edges)}
    return NetworkSpec(
        nodes,
        edges,
        routes,
        bottleneck_edge_starts((PLAIN_LINK, PLAIN_LINK, zip4, zip5)),
        sum(e.length for e in edges),
        closed=False,
        connections=connections,
        internal_links=True,
        main_route=MAIN_ROUTE,
        extra={"scaling": scaling},
    )


class BottleneckNetwork(Network):
    """Flow's ``BottleneckNetwork`` (formerly ``BottleneckScenario``).

    ``net_params.additional_params``: ``scaling`` (lanes are ``4 * scaling`` before the
    bottleneck, ``2 * scaling`` on edge ``4``, ``scaling`` on edge ``5``) and ``speed_limit``
    (m/s). See :data:`ADDITIONAL_NET_PARAMS` and the module docstring.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    PARAM_KINDS: ClassVar[dict[str, str]] = KINDS
    network_type: ClassVar[str] = "bottleneck"

    def build_spec(self) -> NetworkSpec:
        """The bottleneck's nodes, edges, connections and routes."""
        self.scaling = int(self.params["scaling"])
        lights = frozenset(self.traffic_lights.get_properties())  # Flow: named nodes get one
        return bottleneck_spec(self.scaling, float(self.params["speed_limit"]), lights)

    def get_bottleneck_lanes(self, lane: int) -> list[int]:
        """Flow's: the lanes lane ``lane`` of edge ``3`` becomes on edges ``4`` and ``5``."""
        return [int(lane / 2), int(lane / 4)]


#: Flow's older name of the bottleneck.
BottleneckScenario = BottleneckNetwork
