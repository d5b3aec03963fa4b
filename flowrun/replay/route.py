"""Positions along a route of the logged network (time-space diagrams on open roads).

A car's position along a route is where its current edge starts along the route plus its
position on the lane. The route's edges are laid end to end, with the junction-internal edges
(ids starting with ``:``) that connect two consecutive route edges in between, so a car keeps
moving forward while it crosses a junction. Edge and lane lengths and the connections come
from the ``network.net.xml`` the log carries as an attachment: the log alone is enough.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import pairwise, repeat

import numpy as np

from flowrun.errors import RecordingError
from flowrun.recording import McapLog
from flowrun.suggest import did_you_mean
from flowrun.types import FloatArray, IntArray

NET_ATTACHMENT = "network.net.xml"
#: metadata keys written by the run (see ``flowrun.envs.frames.network_metadata``)
MAIN_ROUTE_KEY = "main_route"
CLOSED_KEY = "network_closed"
LENGTH_KEY = "network_length"


def _lane_edge(lane_id: str) -> tuple[str, int]:
    edge, _, index = lane_id.rpartition("_")
    return edge, int(index)


@dataclass
class NetTopology:
    """What a route layout needs from a SUMO network file.

    Attributes:
        edge_length: every edge's length (its longest lane), internal edges included, m.
        lane_length: every lane's length, m.
        links: ``(from edge, to edge)`` -> the lanes a car drives from the first to the
            second, one tuple per lane-to-lane connection (internal lanes, in order; empty
            when the edges meet without a junction-internal lane).
    """

    edge_length: dict[str, float] = field(default_factory=dict)
    lane_length: dict[str, float] = field(default_factory=dict)
    links: dict[tuple[str, str], list[tuple[str, ...]]] = field(default_factory=dict)

    @classmethod
    def parse(cls, net_xml: bytes) -> NetTopology:
        """Read a ``.net.xml``.

        Raises:
            RecordingError: the bytes are not a SUMO network.
        """
        root = parse_net_xml(net_xml)
        top = cls()
        for edge in root.iter("edge"):
            lengths = [float(lane.get("length", "0")) for lane in edge.iter("lane")]
            for lane in edge.iter("lane"):
                top.lane_length[lane.get("id", "")] = float(lane.get("length", "0"))
            top.edge_length[edge.get("id", "")] = max(lengths, default=0.0)
        onward: dict[tuple[str, str], str] = {}  # (internal edge, lane) -> next internal lane
        plain: list[tuple[str, str, str, str]] = []
        for c in root.iter("connection"):
            src, dst = c.get("from", ""), c.get("to", "")
            from_lane, via = c.get("fromLane", "0"), c.get("via", "")
            if src.startswith(":"):
                if via:
                    onward[(src, from_lane)] = via
            else:
                plain.append((src, dst, from_lane, via))
        for src, dst, _, via in sorted(plain, key=lambda p: (p[0], p[1], int(p[2]))):
            chain: list[str] = []
            lane_id = via
            while lane_id and len(chain) < 64:
                chain.append(lane_id)
                internal, index = _lane_edge(lane_id)
                lane_id = onward.get((internal, str(index)), "")
            top.links.setdefault((src, dst), []).append(tuple(chain))
        return top

    def successors(self, edge: str) -> list[str]:
        """The edges a car on ``edge`` may drive onto next."""
        return sorted({dst for src, dst in self.links if src == edge})


@dataclass(frozen=True)
class RouteLayout:
    """Where each edge of a route starts along it.

    Attributes:
        edges: the route's edges, in driving order.
        offsets: start along the route of every edge on it, m: the route's edges and the
            junction-internal edges between consecutive ones.
        length: from the start of the first edge to the end of the last, m.
    """

    edges: tuple[str, ...]
    offsets: dict[str, float]
    length: float

    @property
    def label(self) -> str:
        """The route as ``a → b → c``."""
        return " → ".join(self.edges)

    def edge_starts(self) -> list[tuple[str, float]]:
        """The route's own edges (no internal ones) with their starts, m."""
        return [(e, self.offsets[e]) for e in self.edges]

    def locate(self, edges: Sequence[str], lane_pos: FloatArray) -> tuple[IntArray, FloatArray]:
        """The cars on the route and their positions along it.

        Args:
            edges: every car's edge.
            lane_pos: every car's position on its lane, m.

        Returns:
            the indices of the cars on the route's edges (internal ones between them
            included) and their positions along the route, m.
        """
        start = np.fromiter(map(self.offsets.get, edges, repeat(math.nan)), np.float64, len(edges))
        on = np.flatnonzero(~np.isnan(start))
        return on, start[on] + np.asarray(lane_pos, dtype=np.float64)[on]


def route_layout(net: NetTopology, route: Sequence[str]) -> RouteLayout:
    """Lay a route's edges end to end through the junctions that join them.

    Where several lanes connect two edges, the internal lanes of the first connection
    (lowest lane) set the distance; internal edges of the others start at the same place.

    Raises:
        RecordingError: an edge is not in the network, or two consecutive edges are not
            connected.
    """
    edges = tuple(route)
    if not edges:
        raise RecordingError("--route needs at least one edge, e.g. --route a,b,c")
    for e in edges:
        if e not in net.edge_length:
            names = [n for n in net.edge_length if not n.startswith(":")]
            raise RecordingError(
                f"--route: edge {e!r} is not in the logged network{did_you_mean(e, names)}; "
                f"its edges: {', '.join(sorted(names))}"
            )
    offsets: dict[str, float] = {edges[0]: 0.0}
    pos = 0.0
    for a, b in pairwise(edges):
        chains = net.links.get((a, b))
        if not chains:
            after = ", ".join(net.successors(a)) or "nothing (the road ends)"
            raise RecordingError(
                f"--route: {a!r} does not lead to {b!r} in the logged network; {a!r} leads to "
                f"{after}"
            )
        end = pos + net.edge_length[a]
        for k, chain in enumerate(chains):
            at = end
            for lane in chain:
                offsets.setdefault(_lane_edge(lane)[0], at)
                at += net.lane_length.get(lane, 0.0)
            if k == 0:
                pos = at
        if b in offsets:
            raise RecordingError(f"--route: edge {b!r} appears twice; give a route without loops")
        offsets[b] = pos
    return RouteLayout(edges, offsets, pos + net.edge_length[edges[-1]])


def parse_route(text: str) -> list[str]:
    """``"a,b,c"`` -> ``["a", "b", "c"]``.

    Raises:
        RecordingError: no edge given.
    """
    edges = [e.strip() for e in text.split(",") if e.strip()]
    if not edges:
        raise RecordingError("--route needs comma-separated edge ids, e.g. --route a,b,c")
    return edges


def main_route(log: McapLog) -> list[str]:
    """The network's main road as the run logged it (empty: none recorded, or a ring)."""
    meta = log.metadata
    if meta.get(CLOSED_KEY) == "true":
        return []
    try:
        edges = json.loads(meta.get(MAIN_ROUTE_KEY, "[]") or "[]")
    except json.JSONDecodeError:
        return []
    return [str(e) for e in edges] if isinstance(edges, list) else []


def layout_for(log: McapLog, route: Sequence[str] | None = None) -> RouteLayout | None:
    """The layout of ``route`` on the logged network; without one, of its main road.

    Returns ``None`` when no route is asked for and the log names no main road (rings, and
    logs written before open networks) or carries no network file: plots then use the logged
    network position as before.

    Raises:
        RecordingError: a route is asked for but the log carries no network file, or the route
            is not one of the network's.
    """
    edges = list(route) if route is not None else main_route(log)
    if not edges:
        return None
    data = log.attachments.get(NET_ATTACHMENT)
    if data is None and route is None:
        return None
    if data is None:
        raise RecordingError(
            f"{log.path} has no {NET_ATTACHMENT} attachment, so positions along a route are "
            "unknown; plot without --route"
        )
    return route_layout(NetTopology.parse(data), edges)


def network_length(log: McapLog) -> float:
    """Total length of the logged network, m (``nan`` when the log does not say)."""
    try:
        return float(log.metadata.get(LENGTH_KEY, "nan"))
    except ValueError:
        return math.nan


def parse_net_xml(net_xml: bytes) -> ET.Element:
    """The root ``<net>`` element of a log's attached SUMO network.

    Raises:
        RecordingError: the bytes are not XML, or not a SUMO network.
    """
    try:
        root = ET.fromstring(net_xml)
    except ET.ParseError as err:
        raise RecordingError(f"the log's {NET_ATTACHMENT} is not valid XML: {err}") from err
    if root.tag != "net":
        raise RecordingError(
            f"the log's {NET_ATTACHMENT} is not a SUMO network (root <{root.tag}>)"
        )
    return root
