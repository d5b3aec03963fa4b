"""Every lane of the built network as arrays, and each edge's start along the network.

Read once per episode from SUMO. A lane id maps to an integer *key*; per-step work then looks
up edge, lane index, edge start, speed limit and "junction-internal" by key with numpy.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from flowrun.networks.base import NetworkSpec
from flowrun.types import IntArray


def lane_edge(lane_id: str) -> tuple[str, int]:
    """Edge id and lane index of a SUMO lane id (``edge_3`` -> ``("edge", 3)``)."""
    edge, _, index = lane_id.rpartition("_")
    return edge, int(index)


class LaneTable:
    """The lanes of one network.

    Attributes:
        key: lane id -> key.
        edge_names: edge ids, internal ones included (``edge_index`` points here).
        edge_index, lane_index, start, speed_limit, length, internal: per lane key.
        alone: per lane key, whether it is its edge's only lane (and False at key -1);
            ``alone_l`` the same as a list.
        edge_starts: every edge's start along the network, m (internal edges included).
    """

    def __init__(self, lanes: list[tuple[str, float, float]], links: dict[str, list[Any]],
                 spec: NetworkSpec) -> None:  # fmt: skip
        self.key = {lane: i for i, (lane, _, _) in enumerate(lanes)}
        self.links = links
        edges: dict[str, int] = {}
        edge_index, lane_index = [], []
        for lane, _, _ in lanes:
            edge, idx = lane_edge(lane)
            edge_index.append(edges.setdefault(edge, len(edges)))
            lane_index.append(idx)
        self.edge_names = list(edges)
        self.edge_pos = edges
        self.edge_index = np.array(edge_index, dtype=np.int64)
        self.lane_index = np.array(lane_index, dtype=np.int64)
        self.length = np.array([length for _, length, _ in lanes], dtype=np.float64)
        self.speed_limit = np.array([speed for _, _, speed in lanes], dtype=np.float64)
        self.internal = np.array([lane.startswith(":") for lane, _, _ in lanes], dtype=bool)
        counts = np.bincount(self.edge_index, minlength=len(self.edge_names))
        #: per lane key, whether the lane is its edge's only one; one more entry (False) at
        #: the end, so that key -1 (none) reads False
        self.alone = np.append(counts[self.edge_index] == 1, False)
        self.alone_l: list[bool] = self.alone.tolist()
        #: every edge (internal ones included): (number of lanes, length m, speed limit m/s),
        #: the longest / fastest of its lanes
        self.edge_facts: dict[str, tuple[int, float, float]] = {}
        for (_, length, speed), e in zip(lanes, edge_index, strict=True):
            n, ln, v = self.edge_facts.get(self.edge_names[e], (0, 0.0, 0.0))
            self.edge_facts[self.edge_names[e]] = (n + 1, max(ln, length), max(v, speed))
        self.edge_starts = edge_starts(spec, lanes, links)
        self.start = np.array(
            [self.edge_starts.get(self.edge_names[e], np.nan) for e in edge_index],
            dtype=np.float64,
        )

    @classmethod
    def read(cls, api: Any, spec: NetworkSpec) -> LaneTable:
        """Read the lanes of the running simulation (``libsumo`` or ``traci``)."""
        lane = api.lane
        ids = sorted(lane.getIDList())
        lanes = [(i, float(lane.getLength(i)), float(lane.getMaxSpeed(i))) for i in ids]
        links = {i: list(lane.getLinks(i)) for i in ids}
        return cls(lanes, links, spec)

    def next_lanes(self, edge: str, lane: int) -> list[tuple[str, int]]:
        """Flow's ``next_edge``: where lane ``lane`` of ``edge`` leads, as (edge, lane) pairs;
        through a junction-internal lane when there is one."""
        out = []
        for link in self.links.get(f"{edge}_{lane}", ()):
            out.append(lane_edge(link[4] or link[0]))
        return out

    def prev_lanes(self, edge: str, lane: int) -> list[tuple[str, int]]:
        """Flow's ``prev_edge``: the (edge, lane) pairs leading into lane ``lane`` of ``edge``."""
        target = f"{edge}_{lane}"
        out = []
        for source, links in self.links.items():
            for link in links:
                if link[4] == target or (link[0] == target and not link[4]):
                    out.append(lane_edge(source))
        return out

    def keys(self, lane_ids: list[str]) -> IntArray:
        """Keys of many lane ids."""
        return np.fromiter(map(self.key.__getitem__, lane_ids), np.int64, len(lane_ids))


def edge_starts(
    spec: NetworkSpec, lanes: list[tuple[str, float, float]], links: dict[str, list[Any]]
) -> dict[str, float]:
    """Each edge's start along the network: the spec's, and for junction-internal edges it
    does not list, the end of the edge that leads into them (through chains of internal
    lanes too). Edges of neither kind (a foreign template) are laid end to end after the last.
    """
    starts = dict(spec.edge_starts)
    length = {lane: ln for lane, ln, _ in lanes}
    end = max((s + _edge_length(spec, e) for e, s in starts.items()), default=0.0)
    for lane, ln, _ in lanes:
        edge, _ = lane_edge(lane)
        if edge not in starts and not lane.startswith(":"):
            starts[edge] = end
            end += ln
    frontier = [lane for lane, _, _ in lanes if not lane.startswith(":")]
    while frontier:
        nxt = []
        for lane in frontier:
            edge, _ = lane_edge(lane)
            for link in links.get(lane, ()):
                via = link[4]
                if not via:
                    continue
                via_edge, _ = lane_edge(via)
                if via_edge not in starts and edge in starts:
                    starts[via_edge] = starts[edge] + length[lane]
                    nxt.append(via)
        frontier = nxt
    return starts


def _edge_length(spec: NetworkSpec, edge_id: str) -> float:
    for e in spec.edges:
        if e.id == edge_id:
            return e.length
    return 0.0
