"""Flow's ``MultiRingNetwork`` ("lord of the rings"): ``num_rings`` separate ring roads in one
simulation, laid out on a square grid, each Flow's ring (``bottom_i``, ``right_i``, ``top_i``,
``left_i``).

Ring ``i``'s edges start at ``i * length`` along the network (Flow's edge starts), so absolute
positions of different rings never overlap; each edge's route runs once round its own ring.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, ClassVar

import numpy as np

from flowrun.networks.base import Network
from flowrun.networks.placement import place_on_closed_road, vehicle_space
from flowrun.networks.ring import ring_spec
from flowrun.networks.spec import Edge, NetworkSpec, Node, StartPositions

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # length of each ring road, m
    "length": 230,
    # number of lanes
    "lanes": 1,
    # speed limit of all edges, m/s
    "speed_limit": 30,
    # number of points in each edge's shape (smoothness of the curve)
    "resolution": 40,
    # number of rings
    "num_rings": 7,
}


def multi_ring_spec(p: dict[str, Any]) -> NetworkSpec:
    """``num_rings`` copies of the ring of ``length`` metres, ring ``i`` at grid cell
    ``(i // cols, i % cols)`` with ``cols = ceil(sqrt(num_rings))``, ``4 * radius`` apart
    (Flow's layout), its ids suffixed ``_i``."""
    length, rings = float(p["length"]), int(p["num_rings"])
    one = ring_spec(length, int(p["lanes"]), float(p["speed_limit"]), int(p["resolution"]))
    radius = length / (2 * math.pi)
    cols = math.ceil(math.sqrt(rings))
    nodes: list[Node] = []
    edges: list[Edge] = []
    routes: dict[str, tuple[str, ...]] = {}
    starts: dict[str, float] = {}
    for i in range(rings):
        dx, dy = (i // cols) * 4 * radius, (i % cols) * 4 * radius
        nodes += [replace(n, id=f"{n.id}_{i}", x=n.x + dx, y=n.y + dy) for n in one.nodes]
        edges += [
            replace(
                e, id=f"{e.id}_{i}", from_node=f"{e.from_node}_{i}", to_node=f"{e.to_node}_{i}",
                shape=tuple((x + dx, y + dy) for x, y in e.shape),
            )
            for e in one.edges
        ]  # fmt: skip
        routes |= {f"{s}_{i}": tuple(f"{e}_{i}" for e in r) for s, r in one.routes.items()}
        starts |= {f"{e}_{i}": x + i * length for e, x in one.edge_starts.items()}
    return NetworkSpec(
        tuple(nodes), tuple(edges), routes, starts, rings * length,
        extra={"radius": radius, "num_rings": rings}, internal_links=True,
    )  # fmt: skip


class MultiRingNetwork(Network):
    """Flow's ``MultiRingNetwork``: ``num_rings`` separate rings (see the module docstring).

    ``net_params.additional_params``: ``length`` (m, of each ring), ``lanes``,
    ``speed_limit`` (m/s), ``resolution``, ``num_rings``. Vehicles are shared out over the
    rings in order (the first ``n % k`` rings take one more when ``k`` does not divide ``n``,
    Flow assumes it does), each ring's share placed as on a ring road
    (:func:`~flowrun.networks.placement.place_on_closed_road`).
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    PARAM_KINDS: ClassVar[dict[str, str]] = {
        "length": "positive", "lanes": "count", "speed_limit": "positive",
        "resolution": "resolution", "num_rings": "count",
    }  # fmt: skip
    network_type: ClassVar[str] = "multi_ring"

    def build_spec(self) -> NetworkSpec:
        """The rings' nodes, edges and routes."""
        return multi_ring_spec(self.params)

    def start_positions(self, rng: np.random.Generator) -> StartPositions:
        """Each ring's share of the vehicles, placed on it as on one ring (seeded by ``rng``);
        ``spacing: custom`` or an ``edges_distribution`` uses Flow's general placement."""
        initial = self.initial_config
        if initial.spacing == "custom" or initial.edges_distribution != "all":
            return super().start_positions(rng)
        space = vehicle_space(self.vehicles)
        rings, length = int(self.params["num_rings"]), float(self.params["length"])
        per_edge = len(self.spec.edges) // rings
        edges: list[str] = []
        lane_pos: list[float] = []
        lanes: list[int] = []
        for i, share in enumerate(np.array_split(np.arange(len(space)), rings)):
            positions, ring_lanes = place_on_closed_road(
                length, int(self.params["lanes"]), [space[j] for j in share], initial, rng
            )
            ring_edges = self.spec.edges[i * per_edge : (i + 1) * per_edge]
            for x in positions:
                k = min(int(x // (length / per_edge)), per_edge - 1)
                edges.append(ring_edges[k].id)
                lane_pos.append(float(x - k * length / per_edge))
            lanes += ring_lanes
        return StartPositions(edges, lane_pos, lanes)
