"""Flow's lane leaders and followers of one car: the nearest car ahead and behind on every
lane of its edge, searched on along the next (previous) edges when the edge has none.

This is Flow's ``_multi_lane_headways_util`` rule, as Flow's ``get_lane_leaders``,
``get_lane_headways``, ``get_lane_followers`` and ``get_lane_tailways`` return it:

- on the car's edge, lane by lane, cars sorted by lane position; a car level with this one on
  another lane counts as ahead (its gap is then minus its length);
- where the edge holds no leader (follower) on a lane, the search follows that lane onto the
  first lane it leads to (comes from), junction-internal lanes included, for at most as many
  edges as the network has, adding the lengths of the edges passed;
- headway = leader's position - this car's position (+ lengths passed) - leader's length;
  tailway = this car's position - follower's position (+ lengths passed) - this car's length;
- no car found: ``""`` and a gap of :data:`NO_NEIGHBOUR_GAP` (Flow's 1000 m).

Pure: it reads the positions it is given and asks the lane graph through three callables.
"""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flowrun.flow_values import FLOW_NO_GAP

if TYPE_CHECKING:
    from flowrun.kernel.network import NetworkKernel

#: Flow's gap (m) to a lane's leader or follower when there is none.
NO_NEIGHBOUR_GAP = FLOW_NO_GAP

LaneStep = Callable[[str, int], list[tuple[str, int]]]


@dataclass(frozen=True)
class LaneGraphView:
    """What the search needs of the network.

    Attributes:
        num_lanes: lanes of an edge.
        next_lanes: the (edge, lane) pairs a lane leads to (Flow's ``next_edge``).
        prev_lanes: the (edge, lane) pairs leading into a lane (Flow's ``prev_edge``).
        edge_length: length of an edge, m.
        num_edges: how many edges (junction-internal ones included) a search may pass.
    """

    num_lanes: Callable[[str], int]
    next_lanes: LaneStep
    prev_lanes: LaneStep
    edge_length: Callable[[str], float]
    num_edges: int


def lane_graph(network: NetworkKernel) -> LaneGraphView:
    """The search's view of ``k.network``: its lanes per edge, Flow's ``next_edge`` /
    ``prev_edge`` (the lanes SUMO built; a closed ring's edges in order) and edge lengths."""
    lanes = network.lanes
    count = len(lanes.edge_facts) if lanes is not None else len(network.spec.edges)
    return LaneGraphView(
        network.num_lanes, network.next_edge, network.prev_edge, network.edge_length, count
    )


@dataclass(frozen=True)
class LaneNeighbours:
    """Per lane of the car's edge (index = lane): neighbour rows (-1: none) and gaps, m."""

    leaders: list[int]
    headways: list[float]
    followers: list[int]
    tailways: list[float]


def lane_neighbours(
    me: int,
    edges: Sequence[str],
    lanes: np.ndarray,
    positions: np.ndarray,
    lengths: np.ndarray,
    graph: LaneGraphView,
) -> LaneNeighbours:
    """Flow's lane leaders / followers of the car in row ``me`` (see the module docstring).

    Args:
        me: the car's row.
        edges: every car's edge id, by row.
        lanes: every car's lane index, by row.
        positions: every car's position on its lane, m, by row.
        lengths: every car's length, m, by row.
        graph: the network's lanes.
    """
    by_lane: dict[tuple[str, int], list[int]] = {}
    for row, (edge, lane) in enumerate(zip(edges, lanes.tolist(), strict=True)):
        by_lane.setdefault((edge, int(lane)), []).append(row)
    for rows in by_lane.values():
        rows.sort(key=lambda r: positions[r])  # stable: ties keep row order, as Flow's sort
    this_edge, this_lane, this_pos = edges[me], int(lanes[me]), float(positions[me])
    n = max(int(graph.num_lanes(this_edge)), this_lane + 1)
    leaders, headways = [-1] * n, [NO_NEIGHBOUR_GAP] * n
    followers, tailways = [-1] * n, [NO_NEIGHBOUR_GAP] * n
    for lane in range(n):
        rows = by_lane.get((this_edge, lane), [])
        if rows:
            pos = [float(positions[r]) for r in rows]
            i = bisect_left(pos, this_pos)
            if i < len(rows) - (lane == this_lane):
                j = i + 1 if rows[i] == me else i
                leaders[lane] = rows[j]
                headways[lane] = pos[j] - this_pos - float(lengths[rows[j]])
            if i > 0:
                followers[lane] = rows[i - 1]
                tailways[lane] = this_pos - pos[i - 1] - float(lengths[me])
        if leaders[lane] < 0:
            found = _search(by_lane, graph, this_edge, lane, ahead=True)
            if found is not None:
                row, passed = found
                leaders[lane] = row
                headways[lane] = float(positions[row]) - this_pos + passed - float(lengths[row])
        if followers[lane] < 0:
            found = _search(by_lane, graph, this_edge, lane, ahead=False)
            if found is not None:
                row, passed = found
                followers[lane] = row
                tailways[lane] = this_pos - float(positions[row]) + passed - float(lengths[me])
    return LaneNeighbours(leaders, headways, followers, tailways)


def _search(
    by_lane: dict[tuple[str, int], list[int]],
    graph: LaneGraphView,
    edge: str,
    lane: int,
    ahead: bool,
) -> tuple[int, float] | None:
    """The first car on the lanes ahead of (behind) ``(edge, lane)`` and the length passed:
    the lengths of the edges left behind (ahead: from this edge on; behind: of every edge
    entered, the follower's included)."""
    passed = 0.0
    for _ in range(graph.num_edges):
        step = (graph.next_lanes if ahead else graph.prev_lanes)(edge, lane)
        if not step:
            return None
        if ahead:
            passed += graph.edge_length(edge)
        edge, lane = step[0]
        if not ahead:
            passed += graph.edge_length(edge)
        rows = by_lane.get((edge, lane))
        if rows:
            return (rows[0] if ahead else rows[-1]), passed
    return None
