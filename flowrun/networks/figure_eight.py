"""Flow's figure eight: two 3/4 rings joined by a crossing (a priority junction).

Nodes ``center`` (the crossing, at the origin), ``right``, ``top``, ``left``, ``bottom`` at
distance ``radius_ring`` from it. Straight edges ``bottom`` (bottom -> center), ``top``
(center -> top), ``right`` (right -> center) and ``left`` (center -> left) are each
``radius_ring`` long; the arcs ``upper_ring`` (top -> right) and ``lower_ring``
(left -> bottom) are ``3*pi*radius_ring/2`` long. At the crossing only straight-through
movements exist (``bottom -> top`` and ``right -> left``); ``bottom``/``top`` have priority 78,
``right``/``left`` 46, so the ``right -> left`` stream yields. Every route is the loop of six
edges starting on its edge; a ``ContinuousRouter`` keeps cars going round.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from flowrun.errors import ConfigError
from flowrun.networks.base import Network
from flowrun.networks.checks import check_values
from flowrun.networks.spec import Connection, Edge, NetworkSpec, Node

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # radius of the circular parts, m (also half the length of each straight road)
    "radius_ring": 30,
    # number of lanes
    "lanes": 1,
    # speed limit of all edges, m/s
    "speed_limit": 30,
    # number of points in the shape of each curved edge
    "resolution": 40,
}

KINDS = {"radius_ring": "positive", "lanes": "count", "speed_limit": "positive",
         "resolution": "resolution"}  # fmt: skip

#: the loop in driving order (each route is this loop rotated to start on its edge)
LOOP = ("bottom", "top", "upper_ring", "right", "left", "lower_ring")

INNER_SPACE = 0.28  # Flow's length of the internal link at a ring's end node, m


def junction_length(lanes: int) -> float:
    """Flow's length of the crossing's internal links, m (``2.9 + 3.3 * lanes``)."""
    return 2.9 + 3.3 * lanes


def figure_eight_edge_starts(radius: float, lanes: int) -> dict[str, float]:
    """Flow's positions (m) of each edge along the loop, internal links included.

    The internal edge ids are SUMO's: ``:center_0`` is the ``right -> left`` crossing and
    ``:center_<lanes>`` the ``bottom -> top`` one (netconvert numbers a junction's internal
    edges by link index; ``right``'s ``lanes`` links come first).

    These are Flow's numbers, which assume crossing links of ``2.9 + 3.3 * lanes`` m and
    ring-end links of 0.28 m. SUMO 1.28's netconvert builds the crossing links
    ``3.2 * lanes`` m longer (9.4 m for one lane) and the ring-end links 0.1-0.2 m long, so
    absolute positions on a crossing link run up to ``3.2 * lanes`` m past the next edge's
    start, as they would have in Flow with a newer SUMO.
    """
    # ``ring`` is a quarter circle: each loop is three of them
    ring, cross, junction = radius * math.pi / 2, 2 * radius, junction_length(lanes)
    gap = INNER_SPACE
    return {
        "bottom": gap,
        "top": cross / 2 + junction + gap,
        "upper_ring": cross + junction + 2 * gap,
        "right": cross + 3 * ring + junction + 3 * gap,
        "left": 3 / 2 * cross + 3 * ring + 2 * junction + 3 * gap,
        "lower_ring": 2 * cross + 3 * ring + 2 * junction + 4 * gap,
        ":bottom_0": 0.0,
        f":center_{lanes}": cross / 2 + gap,
        ":top_0": cross + junction + gap,
        ":right_0": cross + 3 * ring + junction + 2 * gap,
        ":center_0": 3 / 2 * cross + 3 * ring + junction + 3 * gap,
        ":left_0": 2 * cross + 3 * ring + 2 * junction + 3 * gap,
    }


def figure_eight_spec(
    radius: float, lanes: int, speed_limit: float, resolution: int
) -> NetworkSpec:
    """Nodes, edges, connections and routes of a figure eight of ``radius`` metres."""
    r = radius
    nodes = (
        Node("center", 0.0, 0.0, "priority", radius=junction_length(lanes) / 2),
        Node("right", r, 0.0),
        Node("top", 0.0, r),
        Node("left", -r, 0.0),
        Node("bottom", 0.0, -r),
    )
    upper = np.linspace(0.0, 3 * math.pi / 2, resolution)
    lower = np.linspace(math.pi / 2, 2 * math.pi, resolution)
    arc = 3 * r * math.pi / 2
    edges = (
        Edge("bottom", "bottom", "center", r, lanes, speed_limit, priority=78),
        Edge("top", "center", "top", r, lanes, speed_limit, priority=78),
        Edge("right", "right", "center", r, lanes, speed_limit, priority=46),
        Edge("left", "center", "left", r, lanes, speed_limit, priority=46),
        Edge("upper_ring", "top", "right", arc, lanes, speed_limit,
             tuple((r * (1 - math.cos(t)), r * (1 + math.sin(t))) for t in upper)),
        Edge("lower_ring", "left", "bottom", arc, lanes, speed_limit,
             tuple((-r + r * math.cos(t), -r + r * math.sin(t)) for t in lower)),
    )  # fmt: skip
    connections = tuple(
        Connection(src, dst, i, i)
        for i in range(lanes)
        for src, dst in (("bottom", "top"), ("right", "left"))
    )
    routes = {LOOP[i]: LOOP[i:] + LOOP[:i] for i in range(len(LOOP))}
    return NetworkSpec(
        nodes,
        edges,
        routes,
        figure_eight_edge_starts(r, lanes),
        4 * r + 2 * arc,
        closed=False,
        extra={"radius_ring": r},
        connections=connections,
        internal_links=True,
        main_route=LOOP,
    )


class FigureEightNetwork(Network):
    """Flow's figure eight (``FigureEightNetwork``, formerly ``Figure8Scenario``).

    ``net_params.additional_params``: ``radius_ring`` (m), ``lanes``, ``speed_limit`` (m/s),
    ``resolution`` (shape points per curved edge). See :data:`ADDITIONAL_NET_PARAMS`.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    network_type: ClassVar[str] = "figure_eight"

    #: Flow's names of the ring-end junction links (its ``specify_internal_edge_starts``),
    #: which ``k.network.get_edge`` answers with
    FLOW_INTERNAL_NAMES: ClassVar[dict[str, str]] = {
        f":{end}_0": f":{end}" for end in ("bottom", "top", "right", "left")
    }

    @classmethod
    def resolve_params(cls, given: dict[str, Any]) -> dict[str, Any]:
        """Merge with defaults and check each value."""
        if "ring_radius" in given:  # the name Flow's own docstring uses
            raise ConfigError(
                "unknown parameter of network 'figure_eight' (did you mean 'radius_ring'? "
                "Flow's docstring says ring_radius, its code reads radius_ring)",
                path="ring_radius",
            )
        params = super().resolve_params(given)
        check_values(params, KINDS)
        return params

    def build_spec(self) -> NetworkSpec:
        """The figure eight's nodes, edges, connections and routes."""
        p = self.params
        return figure_eight_spec(
            float(p["radius_ring"]), int(p["lanes"]), float(p["speed_limit"]),
            int(p["resolution"]),
        )  # fmt: skip


#: Flow's older names of the figure eight.
FigureEightScenario = FigureEightNetwork
Figure8Scenario = FigureEightNetwork
