"""Flow's ``MinicityRouter``: at the end of its route a car drives on to a random next edge.

Flow's rule (``flow/controllers/routing_controllers.py``): a car on its route's last edge
gets the route ``[edge, next]``, ``next`` drawn uniformly among the links of the lane the car
is on (so it never needs a lane change to follow it), and a car on ``e_37`` or ``e_51`` always
gets ``[edge, e_29_u, e_21]``. flowrun draws for all due cars of a group at once from the
kernel's routing generator (seeded by the environment), never from ``random``.

One addition: a hop onto an edge shorter than ``min_edge_length`` (the mini city has
edges of 2 and 5 m) is followed by a further random hop in the same route, so that a car
cannot cross a whole short last edge within one step and leave the network at its end
before the router sees it there. ``min_edge_length=0`` gives Flow's exact one-hop routes.

Routers of this kind (a ``route_vehicles`` method) are driven by :class:`GroupRouters`:
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
    max_hops: int = 8,
) -> list[list[str]]:
    """For cars on ``start_lanes``, a route from their edge through random lane links.

    Each hop follows one of the current lane's links uniformly; hops continue while the edge
    just reached is shorter than ``min_edge_length`` m (at most ``max_hops``). A car whose
    lane has no link gets its edge alone.

    Args:
        start_lanes: the lane id of each car.
        successors: see :func:`lane_successors`.
        edge_length: edge id -> length, m.
        rng: the generator the draws come from (one uniform per car still hopping, per hop).
        min_edge_length: hop on from edges shorter than this, m.
        max_hops: the most hops per route.
    """
    routes = [[lane_edge(lane)] for lane in start_lanes]
    lanes = list(start_lanes)
    active = list(range(len(lanes)))
    for _ in range(max_hops):
        active = [i for i in active if successors.get(lanes[i])]
        if not active:
            break
        counts = np.array([len(successors[lanes[i]]) for i in active])
        picks = draw_indices(counts, rng).tolist()
        for i, k in zip(active, picks, strict=True):
            lanes[i] = successors[lanes[i]][k]
            routes[i].append(lane_edge(lanes[i]))
        active = [i for i in active if edge_length.get(routes[i][-1], 0.0) < min_edge_length]
    return routes


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
        min_edge_length: keep hopping while the edge reached is shorter than this, m; 0 is
            Flow's one hop.
    """

    registered_name = "MinicityRouter"
    #: Flow's fixed routes: a car on one of these edges always continues this way
    FORCED: ClassVar[dict[str, tuple[str, ...]]] = {
        "e_37": ("e_29_u", "e_21"),
        "e_51": ("e_29_u", "e_21"),
    }

    def __init__(
        self, veh_id: str | None = None, router_params: Any = None, min_edge_length: float = 10.0
    ) -> None:
        super().__init__(veh_id, router_params)
        if not min_edge_length >= 0:
            raise ValueError(f"min_edge_length must be >= 0 m, got {min_edge_length}")
        self.min_edge_length = float(min_edge_length)
        self._links_of: Any = None
        self._successors: dict[str, tuple[str, ...]] = {}
        self._lengths: dict[str, float] = {}
        self._forced = np.zeros(0, dtype=bool)

    def choose_route(
        self, current_edge: str, choices: Sequence[RouteChoice], rng: np.random.Generator
    ) -> list[str] | None:
        """Unused: the routes come from :meth:`route_vehicles` (lane links are needed)."""
        return None

    def _bind(self, lanes: Any) -> None:
        """Read the network's lane links and edge lengths (once per built network)."""
        if self._links_of is lanes.links:
            return
        self._links_of = lanes.links
        self._successors = lane_successors(lanes.links)
        self._lengths = {e: float(f[1]) for e, f in lanes.edge_facts.items()}
        self._forced = np.zeros(len(lanes.edge_names), dtype=bool)
        self._forced[[i for e, i in lanes.edge_pos.items() if e in self.FORCED]] = True

    def route_vehicles(
        self, vk: Any, lanes: Any, rows: np.ndarray, rng: np.random.Generator
    ) -> tuple[list[int], list[list[str]]]:
        """New routes for the group's cars that need one.

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
        names, ids = vk.edge_names, vk.table.ids
        edge_index = vk.edge_index[rows]
        at_end = edge_index == vk.route_end[rows]
        todo = np.flatnonzero(at_end | self._forced[edge_index])
        if not todo.size:
            return [], []
        lane_index = vk.lanes[rows[todo]].tolist()
        due: list[tuple[int, str, tuple[str, ...]]] = []
        for j, lane in zip(todo.tolist(), lane_index, strict=True):
            row, edge = int(rows[j]), names[int(edge_index[j])]
            forced = self.FORCED.get(edge, ())
            if forced and tuple(vk.get_route(ids[row])[1 : 1 + len(forced)]) == forced:
                continue  # already on Flow's fixed route
            due.append((row, f"{edge}_{lane}", forced))
        if not due:
            return [], []
        starts, prefixes = [], []
        for _, lane, forced in due:
            reached = follow_edges(lane, forced, self._successors) if forced else lane
            starts.append(reached if reached is not None else lane)
            prefixes.append([lane_edge(lane), *forced] if reached is not None else [])
        tails = random_routes(starts, self._successors, self._lengths, rng, self.min_edge_length)
        out_rows, out_routes = [], []
        for (row, _, forced), prefix, tail in zip(due, prefixes, tails, strict=True):
            if forced and prefix:  # Flow's fixed route, continued at random past a short end
                last_len = self._lengths.get(prefix[-1], 0.0)
                route = prefix + (tail[1:] if last_len < self.min_edge_length else [])
            else:
                route = tail
            if len(route) > 1:
                out_rows.append(row)
                out_routes.append(route)
        return out_rows, out_routes


class GroupRouters:
    """Drives the routers that route a whole vehicle group at once (``route_vehicles``).

    Args:
        routers: ``(group index, router)`` pairs.
    """

    def __init__(self, routers: Sequence[tuple[int, Any]]) -> None:
        self.routers = list(routers)

    @classmethod
    def of(cls, vehicles: Any) -> GroupRouters:
        """The group routers of an experiment's vehicle groups (built from their specs)."""
        from flowrun.controllers.registry import build_controller, resolve_controller

        found = []
        for gi, g in enumerate(vehicles.groups):
            spec = g.routing_controller
            if spec is None:
                continue
            router_cls = spec.cls or resolve_controller(spec.type, "routing")
            if callable(getattr(router_cls, "route_vehicles", None)):
                found.append((gi, build_controller(router_cls, dict(spec.params), "routing")))
        return cls(found)

    def __bool__(self) -> bool:
        return bool(self.routers)

    def step(self, vk: Any, lanes: Any) -> None:
        """Reroute the cars that need it, at once (the kernel calls this at each update,
        before it looks for leaders along the routes)."""
        for gi, router in self.routers:
            rows, routes = router.route_vehicles(vk, lanes, vk.table.rows_of_group(gi), vk.rng)
            if rows:
                vk.reroute_now(rows, routes)
