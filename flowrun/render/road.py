"""The road as drawn: lane polylines, junction outlines and signal heads, from a SUMO network.

A :class:`Road` is read from the ``.net.xml`` every SUMO-backed log carries as its
``network.net.xml`` attachment (and every running kernel has on disk), or built for the numpy
backend's ring, whose road is a circle of known length. Every picture flowrun draws (``--render``,
``rgb_array``, the HTML player, the Foxglove scene) starts from one.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np

from flowrun.errors import RecordingError
from flowrun.types import FloatArray, IntArray

#: SUMO's default lane width, m.
LANE_WIDTH = 3.2


@dataclass(frozen=True)
class Lane:
    """One lane: its SUMO id, centre line (``(n, 2)`` points, m), width and length (m)."""

    id: str
    shape: FloatArray
    width: float
    length: float
    internal: bool


@dataclass(frozen=True)
class SignalHead:
    """Where one traffic-light link is shown: at the end of the lane it lets out.

    Attributes:
        light: the traffic light's id.
        link: index of the link in the light's state string.
        x, y: map position, m (the incoming lane's end, spread across its width when a lane
            has several links).
    """

    light: str
    link: int
    x: float
    y: float


@dataclass
class Road:
    """A network's drawable geometry (map coordinates, m).

    Attributes:
        lanes: every lane, junction-internal ones included.
        junctions: outlines (``(n, 2)`` points) of the junctions that have one.
        signals: one head per traffic-light link.
        source: where the geometry came from (``net.xml`` or ``circle``).
    """

    lanes: list[Lane]
    junctions: list[FloatArray] = field(default_factory=list)
    signals: list[SignalHead] = field(default_factory=list)
    source: str = "net.xml"

    def __post_init__(self) -> None:
        self._index = {lane.id: i for i, lane in enumerate(self.lanes)}
        self._flat: _Polylines | None = None

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of every lane and junction, m (lane widths included)."""
        pts = [lane.shape for lane in self.lanes] + list(self.junctions)
        if not pts:
            return 0.0, 0.0, 1.0, 1.0
        allp = np.concatenate(pts)
        pad = max((lane.width for lane in self.lanes), default=LANE_WIDTH)
        lo, hi = allp.min(axis=0) - pad, allp.max(axis=0) + pad
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])

    def headings(
        self, edges: list[str], lanes: IntArray, lane_pos: FloatArray, x: FloatArray, y: FloatArray
    ) -> FloatArray:
        """Direction of travel (radians, counter-clockwise from +x) of cars at ``lane_pos`` m
        along lane ``lanes[i]`` of ``edges[i]`` (map position ``x``, ``y``); ``nan`` where the
        lane is not in the road. On the numpy ring's circle: the tangent at ``x``, ``y``."""
        n = len(edges)
        if not n:
            return np.zeros(0)
        if self.source == "circle":
            return np.arctan2(np.asarray(y), np.asarray(x)) + math.pi / 2
        index = self._index
        keys = np.fromiter(
            (index.get(f"{e}_{la}", -1) for e, la in zip(edges, lanes.tolist(), strict=True)),
            dtype=np.int64,
            count=n,
        )
        if self._flat is None:
            self._flat = _Polylines(self.lanes)
        return self._flat.headings(keys, np.asarray(lane_pos, dtype=np.float64))


class _Polylines:
    """Every lane's segments laid end to end on one axis: one ``searchsorted`` finds the
    segment of every car (the lane's length is scaled to its drawn shape, as SUMO does)."""

    def __init__(self, lanes: list[Lane]) -> None:
        starts, angles, base, factor = [], [], [], []
        at = 0.0
        for lane in lanes:
            d = np.diff(lane.shape, axis=0)
            seg = np.hypot(d[:, 0], d[:, 1]) if len(d) else np.zeros(1)
            if not len(d):
                d = np.array([[1.0, 0.0]])
            cum = np.concatenate(([0.0], np.cumsum(seg)[:-1]))
            starts.append(at + cum)
            angles.append(np.arctan2(d[:, 1], d[:, 0]))
            base.append(at)
            factor.append(max(0.1, float(seg.sum())) / max(lane.length, 1e-9))
            at += float(seg.sum()) + 1.0
        self.starts = np.concatenate(starts) if starts else np.zeros(1)
        self.angles = np.concatenate(angles) if angles else np.zeros(1)
        self.base = np.array([*base, 0.0])
        self.factor = np.array([*factor, 1.0])

    def headings(self, keys: IntArray, lane_pos: FloatArray) -> FloatArray:
        axis = self.base[keys] + lane_pos * self.factor[keys]
        seg = np.clip(np.searchsorted(self.starts, axis, side="right") - 1, 0, None)
        out = self.angles[seg]
        return np.where(keys >= 0, out, np.nan)


def _points(text: str) -> FloatArray:
    pts = [tuple(float(v) for v in p.split(",")[:2]) for p in text.split()]
    return np.array(pts, dtype=np.float64).reshape(-1, 2)


def road_from_net_xml(data: bytes) -> Road:
    """Parse a SUMO ``.net.xml``: lanes (with ``shape``), junction outlines and, for every
    ``connection`` a traffic light controls, where its signal is shown.

    Raises:
        RecordingError: the bytes are not a SUMO network.
    """
    try:
        root = ET.fromstring(data)
    except ET.ParseError as err:
        raise RecordingError(f"the network file is not valid XML ({err})") from None
    if root.tag != "net":
        raise RecordingError(f"the network file's root is <{root.tag}>, expected SUMO's <net>")
    lanes: list[Lane] = []
    for edge in root.iter("edge"):
        internal = edge.get("function") == "internal"
        for el in edge.iter("lane"):
            shape = _points(el.get("shape", ""))
            if len(shape) < 2:
                continue
            width = float(el.get("width", LANE_WIDTH))
            length = float(el.get("length", "0") or 0) or float(
                np.hypot(*np.diff(shape, axis=0).T).sum()
            )
            lanes.append(Lane(el.get("id", ""), shape, width, length, internal))
    junctions = [
        _points(j.get("shape", ""))
        for j in root.iter("junction")
        if j.get("type") != "internal" and len(j.get("shape", "").split()) >= 3
    ]
    return Road(lanes, junctions, _signal_heads(root, {lane.id: lane for lane in lanes}))


def _signal_heads(root: ET.Element, lanes: dict[str, Lane]) -> list[SignalHead]:
    by_lane: dict[str, list[tuple[str, int]]] = {}
    for con in root.iter("connection"):
        light, link = con.get("tl"), con.get("linkIndex")
        if light is None or link is None:
            continue
        lane_id = f"{con.get('from')}_{con.get('fromLane')}"
        if lane_id in lanes:
            by_lane.setdefault(lane_id, []).append((light, int(link)))
    heads = []
    for lane_id, links in by_lane.items():
        lane = lanes[lane_id]
        end, before = lane.shape[-1], lane.shape[-2]
        d = end - before
        norm = float(np.hypot(*d)) or 1.0
        side = np.array([d[1], -d[0]]) / norm  # to the right of the direction of travel
        for k, (tl, index) in enumerate(sorted(links, key=lambda p: p[1])):
            offset = ((k + 0.5) / len(links) - 0.5) * lane.width
            x, y = end + side * offset
            heads.append(SignalHead(tl, index, float(x), float(y)))
    return heads


def ring_road(length: float, lanes: int = 1, points: int = 96) -> Road:
    """The numpy backend's ring: a circle of circumference ``length`` m around the origin,
    driven counter-clockwise, lane 0 outermost, as the backend places its cars."""
    radius = length / (2 * math.pi)
    theta = np.linspace(-math.pi / 2, 3 * math.pi / 2, points + 1)
    out = []
    for lane in range(lanes):
        r = radius + LANE_WIDTH / 2 + (lanes - 1 - lane) * LANE_WIDTH
        shape = np.stack([r * np.cos(theta), r * np.sin(theta)], axis=1)
        out.append(Lane(f"ring_{lane}", shape, LANE_WIDTH, length, False))
    return Road(out, source="circle")
