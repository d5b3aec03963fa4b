"""Flow's ``k.network``: lengths, edges and positions of the current network (pure lookups)."""

from __future__ import annotations

import bisect

from flowrun.networks.base import NetworkSpec


class NetworkKernel:
    """Read-only facts about the network of the current episode."""

    def __init__(self, spec: NetworkSpec) -> None:
        self.spec = spec
        self._edges = {e.id: e for e in spec.edges}
        self._starts = sorted((s, e) for e, s in spec.edge_starts.items())
        self._max_speed = max(e.speed for e in spec.edges)

    def length(self) -> float:
        """Total length of the network along its edges, m."""
        return self.spec.length

    def edge_length(self, edge_id: str) -> float:
        """Length of one edge, m."""
        return self._edges[edge_id].length

    def get_edge_list(self) -> list[str]:
        """All edge ids."""
        return list(self._edges)

    def num_lanes(self, edge_id: str) -> int:
        """Number of lanes of an edge."""
        return self._edges[edge_id].lanes

    def speed_limit(self, edge_id: str) -> float:
        """Speed limit of an edge, m/s."""
        return self._edges[edge_id].speed

    def max_speed(self) -> float:
        """Highest speed limit in the network, m/s."""
        return self._max_speed

    def get_x(self, edge: str, position: float) -> float:
        """Position along the network of ``position`` metres into ``edge``."""
        return self.spec.edge_starts[edge] + position

    def get_edge(self, x: float) -> tuple[str, float]:
        """Edge and position on it of network position ``x`` (wrapped on closed networks)."""
        if self.spec.closed:
            x = x % self.spec.length
        keys = [s for s, _ in self._starts]
        i = max(bisect.bisect_right(keys, x) - 1, 0)
        start, edge = self._starts[i]
        return edge, x - start

    @property
    def rts(self) -> dict[str, tuple[str, ...]]:
        """Routes by starting edge (Flow's ``rts``)."""
        return dict(self.spec.routes)

    @property
    def total_edgestarts_dict(self) -> dict[str, float]:
        """Start position of every edge (Flow's name)."""
        return dict(self.spec.edge_starts)
