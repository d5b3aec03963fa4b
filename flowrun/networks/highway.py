"""Flow's straight highway: ``num_edges`` equal edges ``highway_0 .. highway_{n-1}``.

Nodes ``edge_0 .. edge_n`` lie on the x axis every ``length / num_edges`` metres. With
``use_ghost_edge`` a downstream edge ``highway_end`` (``boundary_cell_length`` m, speed limit
``ghost_speed_limit``) from ``edge_n`` to ``edge_{n+1}`` ends every route, so cars leaving the
studied section slow down as in the congested road beyond it.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from flowrun.errors import ConfigError
from flowrun.networks.base import Network
from flowrun.networks.spec import Edge, NetworkSpec, Node

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # length of the highway (without the ghost edge), m
    "length": 1000,
    # number of lanes
    "lanes": 4,
    # speed limit of the highway edges, m/s
    "speed_limit": 30,
    # number of edges the highway is divided into
    "num_edges": 1,
    # add the downstream ghost edge `highway_end` with its own speed limit
    "use_ghost_edge": False,
    # speed limit of the ghost edge, m/s
    "ghost_speed_limit": 25,
    # length of the ghost edge, m
    "boundary_cell_length": 500,
}

KINDS = {"length": "positive", "lanes": "count", "speed_limit": "positive",
         "num_edges": "count", "use_ghost_edge": "flag", "ghost_speed_limit": "positive",
         "boundary_cell_length": "positive"}  # fmt: skip

JUNCTION_LENGTH = 0.1  # Flow's length of the link between two highway edges, m


def highway_spec(
    length: float,
    lanes: int,
    speed_limit: float,
    num_edges: int,
    ghost: bool = False,
    ghost_speed_limit: float = 25.0,
    boundary_cell_length: float = 500.0,
) -> NetworkSpec:
    """Nodes, edges, routes and Flow's edge starts of the highway (see the module docstring)."""
    n, seg = num_edges, length / num_edges
    xs = np.linspace(0.0, length, n + 1)
    nodes = [Node(f"edge_{i}", float(xs[i]), 0.0) for i in range(n + 1)]
    edges = [
        Edge(f"highway_{i}", f"edge_{i}", f"edge_{i + 1}", seg, lanes, speed_limit)
        for i in range(n)
    ]
    main = tuple(e.id for e in edges)
    starts = {f"highway_{i}": i * (seg + JUNCTION_LENGTH) for i in range(n)}
    # SUMO's id of the link through node edge_i is ":edge_i_0" (Flow names it ":edge_i")
    starts |= {f":edge_{i + 1}_0": (i + 1) * seg + i * JUNCTION_LENGTH for i in range(n - 1)}
    total = length
    if ghost:
        nodes.append(Node(f"edge_{n + 1}", length + boundary_cell_length, 0.0))
        edges.append(Edge("highway_end", f"edge_{n}", f"edge_{n + 1}", boundary_cell_length,
                          lanes, ghost_speed_limit))  # fmt: skip
        main += ("highway_end",)
        starts["highway_end"] = length + n * JUNCTION_LENGTH
        starts[f":edge_{n}_0"] = length + (n - 1) * JUNCTION_LENGTH
        total += boundary_cell_length
    tail = ("highway_end",) if ghost else ()
    routes = {f"highway_{i}": main[i:n] + tail for i in range(n)}
    return NetworkSpec(
        tuple(nodes),
        tuple(edges),
        routes,
        starts,
        total,
        closed=False,
        internal_links=True,
        main_route=main,
    )


class HighwayNetwork(Network):
    """Flow's highway (``HighwayNetwork``, formerly ``HighwayScenario``).

    ``net_params.additional_params``: ``length`` (m), ``lanes``, ``speed_limit`` (m/s),
    ``num_edges``, ``use_ghost_edge``, ``ghost_speed_limit`` (m/s), ``boundary_cell_length``
    (m). See :data:`ADDITIONAL_NET_PARAMS`.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    PARAM_KINDS: ClassVar[dict[str, str]] = KINDS
    #: Flow's test set-ups give the highway a ring's ``resolution``; Flow ignores it
    UNUSED_FLOW_PARAMS: ClassVar[frozenset[str]] = frozenset({"resolution"})
    network_type: ClassVar[str] = "highway"

    def gen_custom_start_pos(
        self, net_params: Any, initial_config: Any, num_vehicles: int
    ) -> tuple[list[tuple[str, float]], list[int]]:
        """Flow's ``spacing="custom"`` on the highway: the positions and lanes the user lists
        in ``initial_config.additional_params`` (``start_positions``: ``[(edge, pos)]``,
        ``start_lanes``: ``[lane]``), as Flow's highway reads them.

        Raises:
            ConfigError: either list is missing or their lengths differ.
        """
        extra = dict(getattr(initial_config, "additional_params", None) or {})
        missing = [k for k in ("start_positions", "start_lanes") if k not in extra]
        if missing:
            raise ConfigError(
                "initial.spacing 'custom' on the highway reads "
                + " and ".join(f"initial.additional_params.{k}" for k in missing)
                + " ([(edge, position), ...] and [lane, ...]), which are not given",
                path="initial.additional_params",
            )
        positions = [(str(e), float(x)) for e, x in extra["start_positions"]]
        lanes = [int(x) for x in extra["start_lanes"]]
        if len(positions) != len(lanes):
            raise ConfigError(
                f"initial.additional_params: {len(positions)} start_positions but "
                f"{len(lanes)} start_lanes; give one lane per position",
                path="initial.additional_params",
            )
        return positions, lanes

    def build_spec(self) -> NetworkSpec:
        """The highway's nodes, edges and routes."""
        p = self.params
        return highway_spec(
            float(p["length"]), int(p["lanes"]), float(p["speed_limit"]), int(p["num_edges"]),
            bool(p["use_ghost_edge"]), float(p["ghost_speed_limit"]),
            float(p["boundary_cell_length"]),
        )  # fmt: skip


#: Flow's older name of the highway.
HighwayScenario = HighwayNetwork
