"""Leaders and followers on any network: numpy within lanes, the lane graph or SUMO beyond.

Within a lane, cars are sorted by lane position (:func:`leaders_by_lane`). Only the frontmost
car of each occupied lane needs a look past the lane's end, along its route and through
junction-internal lanes. Where the road is unambiguous (one successor, nothing merging, the
route going there, the next car within the look-ahead), the
:class:`~flowrun.kernel.lane_graph.LaneGraph` answers with the rearmost car of the next
occupied lane; elsewhere SUMO's ``getLeader`` (gap minus the ego's ``minGap``, added back)
does. Both give the same cars and gaps (``tests/test_open_kernel.py`` compares every car with
SUMO on every network).

A car's follower is, as in Flow, the car whose leader it is (Flow's kernel sets
``follower`` of each car's leader); where several cars have the same leader (two lanes
merging), the nearest one, and its headway is the tailway. SUMO's ``getFollower`` is not
asked: it can name a car whose leader is someone else (a route that leaves before the
merge) or look less far back.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from flowrun.kernel.following import SMALL, followers_small, leaders_by_lane, leaders_small
from flowrun.kernel.lane_graph import LaneGraph
from flowrun.kernel.population import Population
from flowrun.types import FloatArray, IntArray

#: How far past the end (or before the start) of its lane a car looks for a leader
#: (follower), m. Beyond it IDM's interaction term is below (32 / 500)^2 = 0.4 %.
LOOKAHEAD = 500.0
#: At most this many lanes are walked through before SUMO is asked.
MAX_HOPS = 4
#: At most this many (car, lane) answers of the route look-up are kept.
ROUTE_CACHE = 100_000

Neighbour = Callable[[str, float], Any]
Found = tuple[int, float] | None  # (row, gap) or no neighbour


class Following:
    """Who follows whom on an open network.

    Attributes (after :meth:`compute`, one entry per live car):
        leader, follower: row of the car ahead / behind, -1 for none.
        headway: gap from the front bumper to the leader's rear bumper, m (``inf``: none).
        tailway: gap from the follower's front bumper to this car's rear bumper, m.
        complete: the last :meth:`compute` found a leader and a follower for every car
            (then each car is the leader of exactly one car, so the tailways are the
            followers' headways; known only for few cars, else ``False``).
    """

    def __init__(
        self,
        get_leader: Neighbour,
        graph: LaneGraph | None = None,
        edge_pos: Mapping[str, int] | None = None,
    ) -> None:
        self._get_leader = get_leader
        self.graph = graph
        self._edge_pos = edge_pos or {}
        self.complete = False
        #: (car, lane key) -> (the car's route then, :meth:`_route_next`'s answer)
        self._next_of: dict[tuple[str, int], tuple[tuple[str, ...] | None, int]] = {}

    @classmethod
    def of(cls, api: Any, graph: LaneGraph | None = None,
           edge_pos: Mapping[str, int] | None = None) -> Following:  # fmt: skip
        """Bound to ``libsumo``'s compiled ``getLeader`` (or ``traci``'s)."""
        raw = getattr(api, "_libsumo", None)
        if raw is not None and hasattr(raw, "vehicle_getLeader"):
            return cls(raw.vehicle_getLeader, graph, edge_pos)
        return cls(api.vehicle.getLeader, graph, edge_pos)

    def compute(
        self,
        pop: Population,
        lane_key: IntArray,
        lane_pos: FloatArray,
        routes: Mapping[str, tuple[str, ...]] | None = None,
    ) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
        """Leader, follower, headway and tailway of every live car.

        Args:
            pop: the cars in the network.
            lane_key: each car's lane (:class:`~flowrun.kernel.lanes.LaneTable` key).
            lane_pos: each car's front-bumper position on its lane, m.
            routes: each car's route by id (lets the lane graph answer; SUMO otherwise).
        """
        lengths, min_gaps, ids = pop.lengths, pop.min_gaps, pop.ids
        keys = lane_key.tolist()
        small = len(keys) <= SMALL
        leader: Any
        headway: Any
        if small:  # lists: fewer numpy calls (a per-call cost) for few cars
            pos_l, len_l = lane_pos.tolist(), lengths.tolist()
            leader, headway, fronts, rears = leaders_small(keys, pos_l, len_l)
        else:
            leader, _, headway, front_a, rear_a = leaders_by_lane(lane_key, lane_pos, lengths)
            fronts, rears = front_a.tolist(), rear_a.tolist()
        graph = self.graph if routes is not None else None
        walk = None
        if graph is not None and fronts:
            if not small:
                pos_l, len_l = lane_pos.tolist(), lengths.tolist()
            rear_of = dict(zip([keys[r] for r in rears], rears, strict=True))
            walk = _Walk(graph, keys, pos_l, len_l, rear_of)
        get_leader = self._get_leader
        for r in fronts:
            if walk is not None and routes is not None:
                answer = walk.ahead(r, self._route_next(ids[r], walk.key[r], routes))
                if answer is not _ASK:
                    if answer is not None:
                        leader[r], headway[r] = answer
                    continue
            found = get_leader(ids[r], LOOKAHEAD)
            if found and found[0] and found[0] in pop:
                leader[r] = pop.row(found[0])
                headway[r] = float(found[1]) + float(min_gaps[r])
        if small:
            follower_l, tailway_l = followers_small(leader, headway)
            n = len(keys)
            leader_a = np.fromiter(leader, np.int64, n)
            follower_a = np.fromiter(follower_l, np.int64, n)
            headway_a = np.fromiter(headway, np.float64, n)
            # everyone led and followed: each car leads exactly one, whose headway is its tailway
            self.complete = -1 not in leader and -1 not in follower_l
            tailway_a = headway_a[follower_a] if self.complete else np.array(tailway_l, np.float64)
            return leader_a, follower_a, headway_a, tailway_a
        follower, tailway = followers_of(leader, headway)
        self.complete = False
        return leader, follower, headway, tailway

    def _route_next(self, veh_id: str, key: int, routes: Mapping[str, tuple[str, ...]]) -> int:
        """Edge index of the car's next route edge; -1 on an internal lane (any), -2 at the
        route's end (no leader beyond, as SUMO), -3 unknown (ask SUMO)."""
        graph = self.graph
        assert graph is not None
        if graph.internal_l[key]:
            return -1
        route = routes.get(veh_id)
        cached = self._next_of.get((veh_id, key))
        if cached is not None and cached[0] is route:  # the same route object: same answer
            return cached[1]
        edge = graph.edge_names[graph.edge_index_l[key]]
        if not route or edge not in route:
            want = -3
        else:
            i = route.index(edge)
            want = -2 if i == len(route) - 1 else self._edge_pos.get(route[i + 1], -3)
        if len(self._next_of) >= ROUTE_CACHE:  # (cars come and go: keep it bounded)
            self._next_of.clear()
        self._next_of[veh_id, key] = (route, want)
        return want


class _Ask:
    """Marker: the lane graph cannot answer; ask SUMO."""


_ASK: Any = _Ask()


class _Walk:
    """Walks the lane graph from a lane's front car to the next car ahead."""

    def __init__(self, graph: LaneGraph, lane_key: list[int], lane_pos: list[float],
                 lengths: list[float], rear_of: dict[int, int]) -> None:  # fmt: skip
        self.g = graph
        self.key = lane_key
        self.pos = lane_pos
        self.lengths = lengths
        self.rear_of = rear_of

    def ahead(self, r: int, want: int) -> Found:
        """The leader of front car ``r`` and the gap, ``None``, or :data:`_ASK`."""
        if want == -2:
            return None  # on its route's last edge: SUMO sees no leader beyond
        if want == -3:
            return _ASK
        g, pos = self.g, self.pos
        succ, pred, internal = g.succ_l, g.pred_l, g.internal_l
        cur = self.key[r]
        dist = g.length_l[cur] - pos[r]
        for _ in range(MAX_HOPS):
            nxt = succ[cur]
            # a crossing does not matter ahead (SUMO's leader is on the car's own path), a
            # merge does (a car from the other branch may be the leader)
            if nxt < 0 or pred[nxt] != cur:
                return _ASK
            if not internal[nxt] and want >= 0 and g.edge_index_l[nxt] != want:
                return _ASK
            j = self.rear_of.get(nxt, -1)
            if j >= 0:
                gap = dist + pos[j] - self.lengths[j]
                return (j, gap) if gap <= LOOKAHEAD else _ASK
            if not internal[nxt]:
                return _ASK  # the next edge's lane is empty: SUMO looks further
            dist += g.length_l[nxt]
            cur = nxt
        return _ASK


def followers_of(leader: IntArray, headway: FloatArray) -> tuple[IntArray, FloatArray]:
    """Every car's follower and tailway from everyone's leader and headway (Flow's rule).

    The follower of a car is the car whose leader it is; of several such cars (lanes
    merging), the one with the smallest headway (the lower row on a tie).

    Args:
        leader: row of each car's leader, -1 for none.
        headway: gap from each car's front bumper to its leader's rear bumper, m.

    Returns:
        follower rows (-1 for none) and tailways (m, ``inf`` for none).
    """
    n = leader.shape[0]
    follower = np.full(n, -1, dtype=np.int64)
    tailway = np.full(n, np.inf)
    led = (leader >= 0).nonzero()[0]  # (np.flatnonzero adds a Python layer)
    if led.size:
        order = led[np.lexsort((headway[led], leader[led]))]
        lead_of = leader[order]
        first = np.ones(order.size, dtype=bool)
        first[1:] = lead_of[1:] != lead_of[:-1]
        follower[lead_of[first]] = order[first]
        tailway[lead_of[first]] = headway[order[first]]
    return follower, tailway
