"""Leaders and followers on any network: numpy within lanes, the lane graph or SUMO beyond.

Within a lane, cars are sorted by lane position (:func:`leaders_by_lane`). Only the frontmost
car of each occupied lane needs a look past the lane's end, along its route and through
junction-internal lanes. Where the road is unambiguous (one successor, nothing merging, the
route going there, the next car within the look-ahead), the
:class:`~flowrun.kernel.lane_graph.LaneGraph` answers with the rearmost car of the next
occupied lane; elsewhere SUMO's ``getLeader`` (gap minus the ego's ``minGap``, added back)
does. Both give the same cars and gaps (``tests/test_open_kernel.py`` compares every car with
SUMO on every network). For few cars, while every car stays on its lane, the last step's
order is replayed (checked pair by pair) instead of sorted and walked again: the same
leaders, the same float operations (``_Plan``); the rows around every car are kept as index
arrays while the leaders stay (:class:`~flowrun.kernel.following.Links`).

A car's follower is, as in Flow, the car whose leader it is (Flow's kernel sets
``follower`` of each car's leader); where several cars have the same leader (two lanes
merging), the nearest one, and its headway is the tailway. SUMO's ``getFollower`` is not
asked: it can name a car whose leader is someone else (a route that leaves before the
merge) or look less far back.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from flowrun.kernel.following import (
    SMALL,
    Links,
    followers_small,
    leaders_by_lane,
    leaders_small,
)
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
_INF = float("inf")

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
        links: the last :meth:`compute`'s :class:`~flowrun.kernel.following.Links` when it
            had few cars (``None`` otherwise), made again only when a car's leader changed.
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
        #: the last small compute's order (see :class:`_Plan`)
        self._plan: _Plan | None = None
        #: the last small compute's links (``None`` after a compute of many cars)
        self.links: Links | None = None
        #: the population's lengths array and the same as a list
        self._lengths: tuple[FloatArray, list[float]] | None = None

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
        lists: tuple[list[int], list[float]] | None = None,
    ) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
        """Leader, follower, headway and tailway of every live car.

        Args:
            pop: the cars in the network.
            lane_key: each car's lane (:class:`~flowrun.kernel.lanes.LaneTable` key).
            lane_pos: each car's front-bumper position on its lane, m.
            routes: each car's route by id (lets the lane graph answer; SUMO otherwise).
            lists: ``lane_key`` and ``lane_pos`` as lists, when the caller has them.
        """
        keys = lane_key.tolist() if lists is None else lists[0]
        if len(keys) > SMALL:
            return self._compute_many(pop, keys, lane_key, lane_pos, routes)
        # lists: fewer numpy calls (a per-call cost) for few cars
        pos_l = lane_pos.tolist() if lists is None else lists[1]
        len_l = self._lengths_of(pop)
        plan, found = self._plan, None
        if plan is not None and routes is not None and plan.holds(pop, keys, routes):
            found = self._replay(plan, pop, pos_l, len_l)
        if found is None:
            leader, headway, fronts, rears = leaders_small(keys, pos_l, len_l)
            pairs = [(i, j) for i, j in enumerate(leader) if j >= 0]
            steps = self._look_ahead(pop, keys, pos_l, len_l, fronts, rears, leader, headway,
                                     routes)  # fmt: skip
            self._plan = None if steps is None else _Plan(pop.version, keys, pairs, steps)
        else:
            leader, headway = found
        links = self.links
        if links is None or not links.one_to_one or leader != links.leader_rows:
            # (with the same leaders, each car leading one at most, the followers are the same)
            links = self.links = Links.of(leader, followers_small(leader, headway)[0])
        self.complete = links.complete
        headway_a = np.fromiter(headway, np.float64, len(keys))
        return links.leader, links.follower, headway_a, links.tailway(headway_a)

    def _lengths_of(self, pop: Population) -> list[float]:
        """The cars' lengths as a list (made again when the population's rows change)."""
        if self._lengths is None or self._lengths[0] is not pop.lengths:
            self._lengths = (pop.lengths, pop.lengths.tolist())
        return self._lengths[1]

    def _compute_many(self, pop: Population, keys: list[int], lane_key: IntArray,
                      lane_pos: FloatArray, routes: Mapping[str, tuple[str, ...]] | None,
                      ) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:  # fmt: skip
        """:meth:`compute` on arrays, for many cars."""
        self._plan = self.links = None
        leader, _, headway, fronts, rears = leaders_by_lane(lane_key, lane_pos, pop.lengths)
        self._look_ahead(pop, keys, lane_pos.tolist(), pop.lengths.tolist(), fronts.tolist(),
                         rears.tolist(), leader, headway, routes)  # fmt: skip
        follower, tailway = followers_of(leader, headway)
        self.complete = False
        return leader, follower, headway, tailway

    def _look_ahead(self, pop: Population, keys: list[int], pos_l: list[float],
                    len_l: list[float], fronts: list[int], rears: list[int], leader: Any,
                    headway: Any, routes: Mapping[str, tuple[str, ...]] | None,
                    ) -> list[_Step] | None:  # fmt: skip
        """The leaders of the front cars of the lanes, into ``leader`` and ``headway``: the
        lane graph's where it can tell, SUMO's elsewhere. Returns what was found for each
        front car (:class:`_Plan`), ``None`` without the lane graph."""
        graph = self.graph
        if graph is None or routes is None or not fronts:
            for r in fronts:
                self._ask(pop, r, leader, headway)
            return None
        ids = pop.ids
        walk = _Walk(graph, keys, pos_l, len_l, dict(zip([keys[r] for r in rears], rears,
                                                         strict=True)))  # fmt: skip
        steps: list[_Step] = []
        for r in fronts:
            answer = walk.ahead(r, self._route_next(ids[r], keys[r], routes))
            steps.append((r, routes.get(ids[r]), walk.found))
            if answer is _ASK:
                self._ask(pop, r, leader, headway)
            elif answer is not None:
                leader[r], headway[r] = answer
        return steps

    def _ask(self, pop: Population, r: int, leader: Any, headway: Any) -> None:
        """SUMO's leader of car ``r`` (its gap minus the car's ``minGap``, added back)."""
        found = self._get_leader(pop.ids[r], LOOKAHEAD)
        if found and found[0] and found[0] in pop:
            leader[r] = pop.row(found[0])
            headway[r] = float(found[1]) + float(pop.min_gaps[r])

    def _replay(self, plan: _Plan, pop: Population, pos_l: list[float],
                len_l: list[float]) -> tuple[list[int], list[float]] | None:  # fmt: skip
        """Leaders and headways from the last step's plan (every car on the same lane, the
        same routes), the same floats as :func:`leaders_small` and :meth:`_look_ahead`;
        ``None`` if two cars on a lane changed their order."""
        n = len(pos_l)
        leader, headway = [-1] * n, [_INF] * n
        for a, b in plan.pairs:  # (a car, the car ahead on its lane) in the sort's order
            p, q = pos_l[a], pos_l[b]
            if not (p < q or (p == q and a < b)):
                return None
            leader[a] = b
            headway[a] = q - len_l[b] - p
        graph = self.graph
        assert graph is not None
        length_l, keys = graph.length_l, plan.keys
        for r, _, found in plan.steps:
            if found is None:
                continue  # on its route's last edge
            if found is not _ASK:  # the lane graph's car, through these empty internal lanes
                j, through = found
                dist = length_l[keys[r]] - pos_l[r]
                for k in through:
                    dist += length_l[k]
                gap = dist + pos_l[j] - len_l[j]
                if gap <= LOOKAHEAD:
                    leader[r], headway[r] = j, gap
                    continue
            self._ask(pop, r, leader, headway)
        return leader, headway

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

#: a front car's row, its route then, and its :attr:`_Walk.found`
_Step = tuple[int, "tuple[str, ...] | None", Any]


@dataclass(eq=False)
class _Plan:
    """The order one small :meth:`Following.compute` found, replayed at the next while it holds.

    With every car on the lane it was on and the front cars on the same routes, the leaders
    are the same unless two cars on a lane changed their order (checked pair by pair), and
    the headways are the same float operations on the new positions: within a lane, and past
    its end through the same empty internal lanes to the same car (or SUMO, asked again).

    Attributes:
        version: the population's version; keys: every car's lane key.
        pairs: (car, the car ahead on its lane), every such pair.
        steps: what the look past each lane's end found.
    """

    version: int
    keys: list[int]
    pairs: list[tuple[int, int]]
    steps: list[_Step]

    def holds(self, pop: Population, keys: list[int],
              routes: Mapping[str, tuple[str, ...]]) -> bool:  # fmt: skip
        """The same cars on the same lanes, the front cars on the same routes."""
        if self.version != pop.version or self.keys != keys:
            return False
        ids = pop.ids
        return all(routes.get(ids[r]) is route for r, route, _ in self.steps)


class _Walk:
    """Walks the lane graph from a lane's front car to the next car ahead."""

    def __init__(self, graph: LaneGraph, lane_key: list[int], lane_pos: list[float],
                 lengths: list[float], rear_of: dict[int, int]) -> None:  # fmt: skip
        self.g = graph
        self.key = lane_key
        self.pos = lane_pos
        self.lengths = lengths
        self.rear_of = rear_of
        #: the last :meth:`ahead`'s finding: ``None`` (no leader), :data:`_ASK`, or the rearmost
        #: car of the next occupied lane and the empty internal lanes passed on the way
        self.found: Any = None

    def ahead(self, r: int, want: int) -> Found:
        """The leader of front car ``r`` and the gap, ``None``, or :data:`_ASK`; ``found``
        keeps what decided it apart from the car's position (see :class:`_Plan`)."""
        self.found = None
        if want == -2:
            return None  # on its route's last edge: SUMO sees no leader beyond
        self.found = _ASK
        if want == -3:
            return _ASK
        g, pos = self.g, self.pos
        succ, pred, internal = g.succ_l, g.pred_l, g.internal_l
        cur = self.key[r]
        dist = g.length_l[cur] - pos[r]
        through: list[int] = []
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
                self.found = (j, through)
                gap = dist + pos[j] - self.lengths[j]
                return (j, gap) if gap <= LOOKAHEAD else _ASK
            if not internal[nxt]:
                return _ASK  # the next edge's lane is empty: SUMO looks further
            dist += g.length_l[nxt]
            through.append(nxt)
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
