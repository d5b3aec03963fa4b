"""The road as data: nodes, edges, connections, routes and edge starts (a :class:`NetworkSpec`),
and where vehicles start (:class:`StartPositions`). ``build.py`` turns a spec into SUMO's
``.net.xml``; every network class (``base.Network`` and its subclasses) produces one."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class Node:
    """A junction: id and coordinates in metres."""

    id: str
    x: float
    y: float
    type: str = "priority"
    radius: float | None = None


@dataclass(frozen=True)
class Edge:
    """A road from one node to another.

    Attributes:
        id: edge id.
        from_node: start node id.
        to_node: end node id.
        length: length in metres (forced, so positions add up exactly).
        lanes: number of lanes.
        speed: speed limit, m/s.
        shape: polyline (x, y) points, metres.
        priority: SUMO edge priority (decides right of way at priority junctions).
        spread_type: SUMO ``spreadType``: ``right`` (lanes to the right of the edge's line,
            netconvert's default) or ``center`` / ``roadCenter`` (lanes centred on it).
    """

    id: str
    from_node: str
    to_node: str
    length: float
    lanes: int
    speed: float
    shape: tuple[tuple[float, float], ...] = ()
    priority: int = 78
    spread_type: str = "right"


@dataclass(frozen=True)
class Connection:
    """A lane-to-lane connection through a junction (Flow's ``specify_connections`` entries)."""

    from_edge: str
    to_edge: str
    from_lane: int
    to_lane: int


#: One route choice: the edges driven and the probability of taking it.
RouteChoice = tuple[tuple[str, ...], float]


@dataclass(frozen=True)
class TemplateVehicle:
    """A vehicle of a template's route file, added at every reset (Flow's template vehicles).

    Attributes:
        id: vehicle id.
        type: vehicle type id.
        route: the edges it drives.
        depart: departure time as written, s (it departs that long after the reset).
        depart_pos: SUMO ``departPos`` (text, e.g. ``"12.5"`` or ``"base"``).
        depart_speed: SUMO ``departSpeed`` (text, e.g. ``"0"`` or ``"max"``).
    """

    id: str
    type: str
    route: tuple[str, ...]
    depart: float
    depart_pos: str = "base"
    depart_speed: str = "0"


@dataclass(frozen=True)
class NetworkSpec:
    """Everything SUMO needs to build the road, plus flowrun's own coordinates.

    Attributes:
        nodes: junctions.
        edges: roads, in driving order for closed networks.
        routes: start edge -> the edges of its (most likely) route; vehicles starting on edge
            ``e`` use route ``e``.
        edge_starts: edge id -> position of the edge's start along the network, metres.
            Junction-internal edges (ids starting with ``:``) may be listed; the kernel places
            the ones that are not right after the edge that leads into them.
        length: total length of the network along its edges, metres.
        closed: ``True`` for a ring (positions wrap at ``length``).
        extra: network-specific facts (e.g. the ring's radius).
        connections: lane-to-lane connections; empty lets netconvert decide.
        route_choices: start edge -> ``((edges, probability), ...)`` when a start edge has
            several routes (Flow's ``[(route, prob)]`` form); empty otherwise.
        internal_links: build junction-internal lanes (all networks but the ring, whose
            positions must add up exactly around the loop).
        main_route: the edges of the network's main road, in driving order (time-space
            diagrams follow it); empty means the edges in their listed order.
        net_file: an existing ``.net.xml`` to use as is (``NetParams(template=...)``) instead
            of building one from nodes and edges.
        extra_files: further SUMO route files of a template.
        departures: vehicles added at every reset with a departure time (a template's).
    """

    nodes: tuple[Node, ...]
    edges: tuple[Edge, ...]
    routes: dict[str, tuple[str, ...]]
    edge_starts: dict[str, float]
    length: float
    closed: bool = False
    extra: dict[str, Any] = field(default_factory=dict)
    connections: tuple[Connection, ...] = ()
    route_choices: dict[str, tuple[RouteChoice, ...]] = field(default_factory=dict)
    internal_links: bool = False
    main_route: tuple[str, ...] = ()
    net_file: str | None = None
    extra_files: tuple[str, ...] = ()
    departures: tuple[TemplateVehicle, ...] = ()

    def choices(self, start_edge: str) -> tuple[RouteChoice, ...]:
        """The route choices of vehicles starting on ``start_edge`` (one sure route if fixed)."""
        if start_edge in self.route_choices:
            return self.route_choices[start_edge]
        if start_edge in self.routes:
            return ((self.routes[start_edge], 1.0),)
        return ()


@dataclass(frozen=True)
class StartPositions:
    """Where each vehicle enters: parallel lists in ``VehicleParams.ids`` order.

    Attributes:
        edges: edge id of each vehicle.
        lane_pos: position on that edge, metres (front bumper).
        lanes: lane index.
    """

    edges: list[str]
    lane_pos: list[float]
    lanes: list[int]
