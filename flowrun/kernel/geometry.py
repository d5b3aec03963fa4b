"""Where on the map a lane position is: SUMO's lane-shape interpolation, vectorised.

SUMO places a vehicle at ``shape.positionAtOffset(lane_pos * factor)`` of its lane, with
``factor = max(0.1, shape length) / lane length`` (a lane may be longer or shorter than its
drawn shape) and linear interpolation along the polyline's segments:
``p1 + (p2 - p1) * (offset / |p2 - p1|)``. Doing the same for a whole batch of steps in a few
numpy calls is far cheaper than one ``getPosition`` call per vehicle and step.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from flowrun.types import FloatArray, IntArray

#: SUMO's POSITION_EPS, m: the smallest shape length used for the geometry factor.
POSITION_EPS = 0.1


class LaneGeometry:
    """The drawn shapes of a network's lanes, indexed by ``edge * max_lanes + lane``.

    All lanes' polylines are laid end to end on one axis with a 1 m gap between lanes, so one
    ``searchsorted`` finds the segment of every vehicle at once and no segment joins two lanes.

    Args:
        shapes: ``shapes[e][l]`` is the polyline (``(x, y)`` points, m) of lane ``l`` of edge
            ``e``; edges may have different numbers of lanes.
        lengths: ``lengths[e][l]``, the lane's length in the network, m.
    """

    def __init__(
        self,
        shapes: Sequence[Sequence[Sequence[tuple[float, float]]]],
        lengths: Sequence[Sequence[float]],
    ) -> None:
        self.max_lanes = max((len(lanes) for lanes in shapes), default=1)
        self._base = np.zeros(len(shapes) * self.max_lanes)  # lane start on the common axis
        self._factor = np.ones(len(shapes) * self.max_lanes)
        points: list[FloatArray] = []
        local: list[FloatArray] = []
        axis: list[FloatArray] = []
        start = 0.0
        for e, lanes in enumerate(shapes):
            for lane, shape in enumerate(lanes):
                pts = np.asarray(shape, dtype=np.float64).reshape(-1, 2)
                step = pts[1:] - pts[:-1]
                seg = np.sqrt(step[:, 0] * step[:, 0] + step[:, 1] * step[:, 1])
                cum = np.concatenate(([0.0], np.cumsum(seg)))  # summed in order, as SUMO does
                index = e * self.max_lanes + lane
                self._base[index] = start
                self._factor[index] = max(POSITION_EPS, float(cum[-1])) / float(lengths[e][lane])
                points.append(pts)
                local.append(cum)
                axis.append(start + cum)
                start += float(cum[-1]) + 1.0
        self._p = np.concatenate(points) if points else np.zeros((0, 2))
        self._local = np.concatenate(local) if local else np.zeros(0)
        self._axis = np.concatenate(axis) if axis else np.zeros(0)
        # Segment i runs from point i to point i + 1; a lane's last point starts a segment
        # into the next lane's first point that only a position at the very end reaches
        # (with fraction 0).
        following = np.concatenate((self._p[1:], self._p[-1:]))
        self._d = following - self._p
        dist = np.sqrt(self._d[:, 0] * self._d[:, 0] + self._d[:, 1] * self._d[:, 1])
        self._dist = np.where(dist > 0.0, dist, 1.0)

    def xy(
        self, edge: IntArray, lane: IntArray | int, lane_pos: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """``(x, y)`` of vehicles at ``lane_pos`` m into lane ``lane`` of edge ``edge`` (any
        array shapes that broadcast together)."""
        index = edge * self.max_lanes + lane
        offset = lane_pos * self._factor[index]  # along the drawn shape, m
        seg = np.searchsorted(self._axis, self._base[index] + offset, side="right") - 1
        frac = (offset - self._local[seg]) / self._dist[seg]
        p, d = self._p[seg], self._d[seg]
        return p[..., 0] + d[..., 0] * frac, p[..., 1] + d[..., 1] * frac


class RingEdges:
    """Which edge a ring position is on, and how far along it (any array shape).

    Args:
        starts: where each edge starts along the ring, m (ascending).
        names: edge ids, in the order of ``starts``.
    """

    def __init__(self, starts: FloatArray, names: Sequence[str]) -> None:
        self.starts = starts
        self.names = np.array(names, dtype=object)

    def index(self, position: FloatArray) -> IntArray:
        """Edge index of each ring position."""
        return np.searchsorted(self.starts, position, side="right") - 1

    def locate(self, position: FloatArray) -> tuple[IntArray, FloatArray]:
        """Edge index and position on the lane (m) of each ring position."""
        edge = self.index(position)
        return edge, position - self.starts[edge]

    def edge_names(self, edge: IntArray) -> list[Any]:
        """Edge ids for an array of edge indices (nested lists for a 2-d array)."""
        result: list[Any] = self.names[edge].tolist()
        return result


class RingPlacement:
    """Map coordinates of ring positions, for whole batches of steps: the edge and lane
    position (:class:`RingEdges`, as the per-step snapshot derives them) on the lane shapes.

    Args:
        edges: the ring's edges.
        geometry: the lanes' drawn shapes.
    """

    def __init__(self, edges: RingEdges, geometry: LaneGeometry) -> None:
        self.edges = edges
        self.geometry = geometry

    def xy(self, position: FloatArray, lanes: IntArray) -> tuple[FloatArray, FloatArray]:
        """Map coordinates (m) of ring positions on the given lanes."""
        edge, lane_pos = self.edges.locate(position)
        return self.geometry.xy(edge, lanes, lane_pos)
