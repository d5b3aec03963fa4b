"""Flow's ``MinicityRouter``: at the end of its route a car drives on to a random next edge.

Flow's rule (``flow/controllers/routing_controllers.py``): a car on its route's last edge
gets the route ``[edge, next]``, ``next`` drawn uniformly among the links of the lane the car
is on (so it never needs a lane change to follow it), and a car on ``e_37`` or ``e_51`` always
gets ``[edge, e_29_u, e_21]``. flowrun draws for all due cars of a group at once from the
kernel's routing generator (seeded by the environment), never from ``random``.

Two additions, each a parameter (both 0 give Flow's one-hop routes):

- ``lookahead`` (m): the random hops are drawn ahead until the route reaches at least this
  far beyond the car's edge, and drawn further before the car gets closer to the route's
  end. SUMO's drivers and flowrun's leaders look only along a car's route, so with one-hop
  routes a car drives blind into a queue just past its route's end (and rear-ends it).
  Each next edge is still drawn uniformly among the links of the lane the car will be on.
- ``min_edge_length`` (m): a route never ends on an edge shorter than this (the mini city
  has edges of 2 and 5 m), so a car cannot cross its route's whole last edge within one
  step and leave the network at its end before the router sees it there.

Routers of this kind (a ``route_vehicles`` method) are driven by
:class:`~flowrun.controllers.drivers.GroupRouters`:
the kernel runs them at every update, right after reading where the cars are and before
looking for leaders along the routes (as it does for ``ContinuousRouter``), so a car never
sits on its route's last edge in an observed state.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import numpy as np

from flowrun.controllers.routing import RouteChoice, Router

#: lane id -> the lanes (not junction-internal) its links lead to, in SUMO's link order
Successors = Mapping[str, Sequence[str]]


def lane_edge(lane_id: str) -> str:
    """The edge of a SUMO lane id (``e_8_b_1`` -> ``e_8_b``)."""
    return lane_id.rpartition("_")[0]


def lane_successors(links: Mapping[str, Sequence[Sequence[Any]]]) -> dict[str, tuple[str, ...]]:
    """Every lane's successor lanes from SUMO's ``lane.getLinks`` answers (a link's first
    item is the next lane that is not junction-internal)."""
    return {lane: tuple(str(link[0]) for link in out) for lane, out in links.items()}


def draw_indices(counts: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One index in ``[0, count)`` per entry, uniformly (all entries with ``count >= 1``)."""
    counts = np.asarray(counts, dtype=np.int64)
    return np.minimum((rng.random(counts.size) * counts).astype(np.int64), counts - 1)


def random_routes(
    start_lanes: Sequence[str],
    successors: Successors,
    edge_length: Mapping[str, float],
    rng: np.random.Generator,
    min_edge_length: float = 0.0,
    lookahead: float = 0.0,
    base: Sequence[float] | None = None,
    min_hops: Sequence[int] | None = None,
    max_hops: int = 32,
) -> tuple[list[list[str]], list[str]]:
    """For cars on ``start_lanes``, random hops through lane links from their edge.

    Each hop follows one of the current lane's links uniformly. A car hops at least
    ``min_hops`` times (default 1), then on while its hops cover less than
    ``lookahead - base`` m or the edge just reached is shorter than ``min_edge_length`` m, at
    most ``max_hops`` times; a lane without links ends the hops.

    Args:
        start_lanes: the lane id each car hops from.
        successors: see :func:`lane_successors`.
        edge_length: edge id -> length, m.
        rng: the generator the draws come from (one uniform per car still hopping, per hop).
        min_edge_length: never stop on an edge shorter than this, m.
        lookahead: the distance the hops (plus ``base``) should cover, m.
        base: per car, the distance already covered before the first hop, m (default 0).
        min_hops: per car, the hops to make in any case (default 1).
        max_hops: the most hops per car.

    Returns:
        Per car, its start edge followed by the edges hopped onto, and the lane it ends on.
    """
    n = len(start_lanes)
    routes = [[lane_edge(lane)] for lane in start_lanes]
    lanes = list(start_lanes)
    covered = [0.0] * n if base is None else [float(b) for b in base]
    least = [1] * n if min_hops is None else list(min_hops)
    hops = [0] * n

    def go_on(i: int) -> bool:
        if hops[i] < least[i]:
            return True
        return covered[i] < lookahead or edge_length.get(routes[i][-1], 0.0) < min_edge_length

    active = [i for i in range(n) if go_on(i)]
    for _ in range(max_hops):
        active = [i for i in active if successors.get(lanes[i])]
        if not active:
            break
        counts = np.array([len(successors[lanes[i]]) for i in active])
        picks = draw_indices(counts, rng).tolist()
        for i, k in zip(active, picks, strict=True):
            lanes[i] = successors[lanes[i]][k]
            edge = lane_edge(lanes[i])
            routes[i].append(edge)
            covered[i] += edge_length.get(edge, 0.0)
            hops[i] += 1
        active = [i for i in active if go_on(i)]
    return routes, lanes


def trigger_index(
    route: Sequence[str], edge_length: Mapping[str, float], lookahead: float, min_edge_length: float
) -> int:
    """Where along ``route`` (the car on ``route[0]``) the router must draw further hops:
    the first later edge at whose end less than ``lookahead`` m of route would remain,
    moved on past edges shorter than ``min_edge_length`` (a car may cross them unseen);
    the last edge when the route never gets that short."""
    lengths = [edge_length.get(e, 0.0) for e in route]
    last = len(route) - 1
    after = 0.0
    remaining = [0.0] * len(route)  # route left beyond the end of each edge
    for i in range(last, -1, -1):
        remaining[i] = after
        after += lengths[i]
    index = next((i for i in range(1, last + 1) if remaining[i] < lookahead), last)
    while index < last and lengths[index] < min_edge_length:
        index += 1
    return max(index, min(1, last))


def follow_edges(lane: str, edges: Sequence[str], successors: Successors) -> str | None:
    """The lane reached from ``lane`` along ``edges`` (first link onto each), or ``None``."""
    for edge in edges:
        lane_next = next((s for s in successors.get(lane, ()) if lane_edge(s) == edge), None)
        if lane_next is None:
            return None
        lane = lane_next
    return lane


class MinicityRouter(Router):
    """Flow's ``MinicityRouter`` (see the module docstring).

    Args:
        veh_id: Flow's vehicle id (informative).
        router_params: Flow's ``router_params`` (kept as given).
        lookahead: draw the next edges this far ahead of the car, m (0: Flow's one hop).
        min_edge_length: never end a route on an edge shorter than this, m.
    """

    registered_name = "MinicityRouter"
    #: Flow's fixed routes: a car on one of these edges always continues this way
    FORCED: ClassVar[dict[str, tuple[str, ...]]] = {
        "e_37": ("e_29_u", "e_21"),
        "e_51": ("e_29_u", "e_21"),
    }

    def __init__(
        self,
        veh_id: str | None = None,
        router_params: Any = None,
        lookahead: float = 60.0,
        min_edge_length: float = 10.0,
    ) -> None:
        super().__init__(veh_id, router_params)
        for name, value in (("lookahead", lookahead), ("min_edge_length", min_edge_length)):
            if not value >= 0:
                raise ValueError(f"{name} must be >= 0 m, got {value}")
        self.lookahead = float(lookahead)
        self.min_edge_length = float(min_edge_length)
        self._links_of: Any = None
        self._successors: dict[str, tuple[str, ...]] = {}
        self._lengths: dict[str, float] = {}
        self._forced = np.zeros(0, dtype=bool)
        self._edge_pos: Mapping[str, int] = {}
        #: per car: the route given, the lane it ends on, and the edge to extend it on
        self._plan: dict[str, tuple[tuple[str, ...], str, int]] = {}

    def choose_route(
        self, current_edge: str, choices: Sequence[RouteChoice], rng: np.random.Generator
    ) -> list[str] | None:
        """Unused: the routes come from :meth:`route_vehicles` (lane links are needed)."""
        return None

    def _bind(self, lanes: Any) -> None:
        """Read the network's lane links and edge lengths (once per started simulation)."""
        if self._links_of is lanes.links:
            return
        self._links_of = lanes.links
        self._successors = lane_successors(lanes.links)
        self._lengths = {e: float(f[1]) for e, f in lanes.edge_facts.items()}
        self._edge_pos = lanes.edge_pos
        self._forced = np.zeros(len(lanes.edge_names), dtype=bool)
        self._forced[[i for e, i in lanes.edge_pos.items() if e in self.FORCED]] = True
        self._plan = {}

    def _extend(
        self,
        ids: Sequence[str],
        rows: list[int],
        kept: list[tuple[str, ...]],
        hops: list[list[str]],
        ends: list[str],
    ) -> tuple[list[int], list[list[str]]]:
        """The cars' kept routes extended by their hops (a car at a dead end gets none), and
        each car's plan: its route, the lane it ends on and the edge to extend it on next."""
        out_rows, out_routes = [], []
        for row, route, tail, end_lane in zip(rows, kept, hops, ends, strict=True):
            new = (*route, *tail[1:])
            if len(new) == 1:
                continue  # a dead end: nothing to add
            at = trigger_index(new, self._lengths, self.lookahead, self.min_edge_length)
            self._plan[ids[row]] = (new, end_lane, self._edge_pos.get(new[at], -1))
            out_rows.append(row)
            out_routes.append(list(new))
        return out_rows, out_routes

    def _kept_route(
        self, veh_id: str, edge: str, lane_no: int, at_end: bool, at_trigger: bool
    ) -> tuple[tuple[str, ...], str] | None:
        """The part of a due car's route it keeps (from ``edge`` on) and the lane that part
        ends on, or ``None`` when the car needs no new route after all (already on Flow's
        fixed way on, or unable to take it before its route's end)."""
        lane = f"{edge}_{lane_no}"
        route: tuple[str, ...] = (edge,)
        end_lane = lane
        given = self._plan.get(veh_id)
        if given is not None and edge in given[0]:
            at = len(given[0]) - 1 - given[0][::-1].index(edge)
            route, end_lane = given[0][at:], given[1]
        forced = self.FORCED.get(edge, ())
        if forced and route[1 : 1 + len(forced)] != forced:
            reached = follow_edges(lane, forced, self._successors)
            if reached is not None:
                return (edge, *forced), reached
            return (route, end_lane) if at_end else None
        if not at_end and not at_trigger:
            return None  # already on Flow's fixed way on
        return route, end_lane

    def route_vehicles(
        self, vk: Any, lanes: Any, rows: np.ndarray, rng: np.random.Generator
    ) -> tuple[list[int], list[list[str]]]:
        """New routes for the group's cars that need one.

        A car needs one on its route's last edge, on the edge where its route gets shorter
        than ``lookahead`` ahead, and on ``e_37``/``e_51`` off Flow's fixed way on.

        Args:
            vk: the vehicle kernel, its state of this step read (edges, lanes, route ends).
            lanes: the network's lanes (:class:`~flowrun.kernel.lanes.LaneTable`).
            rows: the group's rows in the vehicle arrays.
            rng: the generator of the random choices.

        Returns:
            The rows of the cars to reroute and their new routes.
        """
        if lanes is None or not rows.size:
            return [], []
        self._bind(lanes)
        names, ids, plan = vk.edge_names, vk.table.ids, self._plan
        row_list = rows.tolist()
        edge_index = vk.edge_index[rows]
        route_end = vk.route_end[rows]
        trigger = np.fromiter(
            (plan[ids[r]][2] if ids[r] in plan else -1 for r in row_list), np.int64, rows.size
        )
        due_mask = (edge_index == route_end) | (edge_index == trigger) | self._forced[edge_index]
        todo = np.flatnonzero(due_mask)
        if not todo.size:
            return [], []
        lane_index = vk.lanes[rows[todo]].tolist()
        due_rows, kept, starts, base, least = [], [], [], [], []
        for j, lane_no in zip(todo.tolist(), lane_index, strict=True):
            row, edge = row_list[j], names[int(edge_index[j])]
            at_end, at_trigger = edge_index[j] == route_end[j], edge_index[j] == trigger[j]
            kept_route = self._kept_route(ids[row], edge, lane_no, at_end, at_trigger)
            if kept_route is None:
                continue
            route, end_lane = kept_route
            due_rows.append(row)
            kept.append(route)
            starts.append(end_lane)
            base.append(sum(self._lengths.get(e, 0.0) for e in route[1:]))
            least.append(1 if len(route) == 1 else 0)
        hops, ends = random_routes(
            starts, self._successors, self._lengths, rng,
            self.min_edge_length, self.lookahead, base, least,
        )  # fmt: skip
        out_rows, out_routes = self._extend(ids, due_rows, kept, hops, ends)
        if len(plan) > 2 * len(ids) + 64:  # forget cars that left
            live = set(ids)
            self._plan = {v: p for v, p in plan.items() if v in live}
        return out_rows, out_routes
