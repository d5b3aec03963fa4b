"""Flow's mini city: a small hard-coded town of two roundabouts, a ring road and a grid.

Everything is fixed (Flow's ``SCALING = 40``): 45 nodes and 95 edges named as in Flow
(``n_i1`` .., ``e_1`` .. ``e_94``, with ``e_8_b``/``e_8_u``, ``e_28_b``, ``e_29_u``), one or
two lanes each, all at 30 m/s; the facts are in :mod:`flowrun.networks.minicity_data`. Every
route is a single edge (``{e: [e]}``): cars are meant to be driven by
:class:`~flowrun.controllers.minicity_router.MinicityRouter`, which picks each next edge at
random. Positions along the network (``get_x_by_id``) lay the edges end to end in Flow's
order (Flow's ``specify_edge_starts``); junction-internal edges follow the edge leading into
them.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from flowrun.errors import ConfigError
from flowrun.networks.base import Network
from flowrun.networks.minicity_data import (
    ARCS,
    CONNECTIONS,
    EDGES,
    FORCED_LENGTHS,
    NODES,
    RESOLUTION,
    SCALING,
    SPEED,
)
from flowrun.networks.spec import Connection, Edge, NetworkSpec, Node

#: Flow's MiniCity takes no parameters.
ADDITIONAL_NET_PARAMS: dict[str, Any] = {}


def node_positions() -> dict[str, tuple[float, float]]:
    """Every node's (x, y), m."""
    return {nid: (x * SCALING, y * SCALING) for nid, x, y in NODES}


def edge_geometry(
    edge_id: str, from_node: str, to_node: str, nodes: dict[str, tuple[float, float]]
) -> tuple[float, tuple[tuple[float, float], ...]]:
    """An edge's length (m) and shape (m; empty for a straight edge), as Flow computes them:
    the forced length if Flow forces one, else the arc polyline's or the nodes' distance."""
    arc = ARCS.get(edge_id)
    shape: tuple[tuple[float, float], ...] = ()
    if arc is None:
        (x0, y0), (x1, y1) = nodes[from_node], nodes[to_node]
        length = float(np.hypot(x1 - x0, y1 - y0))
    else:
        pts = arc.points(RESOLUTION)
        length = float(np.sum(np.hypot(*np.diff(pts, axis=0).T) * SCALING))
        shape = tuple((float(x) * SCALING, float(y) * SCALING) for x, y in pts)
    return float(FORCED_LENGTHS.get(edge_id, length)), shape


def minicity_spec() -> NetworkSpec:
    """Nodes, edges, connections, single-edge routes and edge starts of the mini city."""
    positions = node_positions()
    nodes = tuple(Node(nid, x, y) for nid, (x, y) in positions.items())
    edges = []
    for eid, a, b, lanes in EDGES:
        length, shape = edge_geometry(eid, a, b, positions)
        edges.append(Edge(eid, a, b, length, lanes, SPEED, shape))
    starts, total = {}, 0.0
    for e in edges:  # Flow's specify_edge_starts: end to end in the listed order
        starts[e.id] = total
        total += e.length
    return NetworkSpec(
        nodes,
        tuple(edges),
        {e.id: (e.id,) for e in edges},
        starts,
        total,
        closed=False,
        connections=tuple(Connection(*c) for c in CONNECTIONS),
        internal_links=True,
    )


class MiniCityNetwork(Network):
    """Flow's ``MiniCityNetwork``: a fixed small city (see the module docstring).

    It takes no ``net_params.additional_params`` (Flow's ``ADDITIONAL_NET_PARAMS`` is empty);
    give its cars ``MinicityRouter`` so they keep driving from edge to edge.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    network_type: ClassVar[str] = "minicity"
    LIST_NOTE: ClassVar[str] = "no parameters: Flow's fixed small city; cars use MinicityRouter"

    @classmethod
    def resolve_params(cls, given: dict[str, Any]) -> dict[str, Any]:
        """No parameters: any key is an error.

        Raises:
            ConfigError: a parameter was given.
        """
        for key in given:
            raise ConfigError(
                "unknown parameter of network 'minicity': Flow's mini city is fixed and takes "
                "no parameters; remove it",
                path=str(key),
            )
        return {}

    def build_spec(self) -> NetworkSpec:
        """The mini city's nodes, edges, connections and routes."""
        self.nodes_dict = {n: np.array(xy) for n, xy in node_positions().items()}
        return minicity_spec()


#: Flow's older name.
MiniCityScenario = MiniCityNetwork
