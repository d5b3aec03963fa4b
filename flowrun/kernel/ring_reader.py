"""The closed ring's reader: two getters per car and one sort around the loop.

On a ring whose cars all circle forever (``ContinuousRouter``) nobody enters or leaves, so the
rows never change. Each update reads every car's speed and odometer (and lane on several
lanes, map coordinates when asked for); the ring position is the entry position plus the
odometer (equal to SUMO's edge offset + lane position to ~1e-13 m), and leaders come from the
cars' order around the loop (:class:`~flowrun.kernel.following.RingFollowing`).
"""

from __future__ import annotations

from collections import deque
from itertools import chain
from typing import TYPE_CHECKING, Any

import numpy as np

from flowrun.errors import SimulationError
from flowrun.kernel.following import RingFollowing, leaders_on_ring, neighbours
from flowrun.kernel.geometry import LaneGeometry, RingEdges, RingPlacement
from flowrun.kernel.state import RingState
from flowrun.types import FloatArray, IntArray

if TYPE_CHECKING:
    from collections.abc import Sequence

    from flowrun.kernel.population import Population, VehicleTable
    from flowrun.kernel.sumo import FastCalls
    from flowrun.networks.base import NetworkSpec

_flatten = chain.from_iterable


def ring_fast_path(spec: NetworkSpec, initial: VehicleTable) -> bool:
    """Whether the closed-ring reader applies: a ring whose cars all circle forever
    (``ContinuousRouter``), so nobody enters or leaves. A car without it leaves the ring at
    its route's end, as in Flow, and the open road's reader follows it."""
    return spec.closed and all(initial.classes[g].continuous for g in set(initial.group.tolist()))


class RingReader:
    """Reads the cars of a closed ring (see the module doc).

    Args:
        table: the population (fixed on a ring).
        initial: the cars placed at the start (their entry edges and positions).
        spec: the ring.
        dt: simulation step, s.
        api: ``libsumo`` or ``traci``; fast: its compiled getters.

    Attributes:
        read_xy_each_step: map coordinates are read at every update.
        departed_ids, arrived_ids, flow_counts: always empty (nobody enters or leaves).
        rows_changed: always ``False``.
    """

    #: nobody enters or leaves a closed ring
    departed_ids: Sequence[str] = ()
    arrived_ids: Sequence[str] = ()
    rows_changed = False
    #: a ring keeps no lane table (lanes come from the spec)
    lanes: None = None

    def __init__(self, table: Population, initial: VehicleTable, spec: NetworkSpec, dt: float,
                 api: Any, fast: FastCalls) -> None:  # fmt: skip
        self.table, self.spec, self.dt, self.api, self.fast = table, spec, dt, api, fast
        self.read_xy_each_step = True
        self.flow_counts: deque[tuple[int, int]] = deque(maxlen=1)
        #: the state of the last update
        self.last: RingState | None = None
        #: routes' last edges are not kept on a ring (no lane table)
        self.route_end = np.full(table.size, -1, dtype=np.int64)
        self.multi_lane = any(e.lanes > 1 for e in spec.edges)
        self._edge_ids = [e.id for e in spec.edges]
        self._edge_pos = {e: i for i, e in enumerate(self._edge_ids)}
        self._starts = np.array([spec.edge_starts[e] for e in self._edge_ids])
        self.ring_edges = RingEdges(self._starts, self._edge_ids)
        self._edge_speeds = np.array([e.speed for e in spec.edges])
        self._uniform_speed = bool(np.all(self._edge_speeds == self._edge_speeds[0]))
        start_idx = np.array(
            [self._edge_pos.get(e, 0) for e in initial.start_edges], dtype=np.int64
        )
        self._start_position = self._starts[start_idx] + np.array(initial.start_lane_pos)
        self._following = RingFollowing(table.lengths, spec.length)
        self._any_continuous = bool(table.continuous.any())
        n = table.size
        self._speed_limit = np.full(n, self._edge_speeds[0])
        self._on_internal = np.zeros(n, dtype=bool)
        self._lane_index = np.zeros(n, dtype=np.int64)
        self._x, self._y = np.zeros(n), np.zeros(n)
        # A route runs once around the ring from its first edge, so its last edge is the one
        # before: ContinuousRouter gives a car its next loop when its odometer reaches it.
        self._next_reroute = np.where(
            table.continuous, self._distance_to_route_end(start_idx, self._start_position), np.inf
        )
        fastest = max(float(self._edge_speeds.max()), float(table.max_speeds.max(initial=0.0)))
        self._max_step_distance = 2.0 * fastest * dt + 1e-9
        self._reroute_wait = 0

    def placement(self) -> RingPlacement:
        """Edges, lane positions and map coordinates of ring positions, for batches of steps,
        on the network of this episode (reads the lane shapes once)."""
        lane = self.api.lane
        edges = self.spec.edges
        geometry = LaneGeometry(
            [[lane.getShape(f"{e.id}_{i}") for i in range(e.lanes)] for e in edges],
            [[lane.getLength(f"{e.id}_{i}") for i in range(e.lanes)] for e in edges],
        )
        return RingPlacement(self.ring_edges, geometry)

    def _distance_to_route_end(self, edge_idx: IntArray, position: FloatArray) -> FloatArray:
        last = np.mod(edge_idx - 1, len(self._edge_ids))
        return np.mod(self._starts[last] - position, self.spec.length)

    def read(self, first: bool, removed: list[str]) -> RingState:
        """This step's state, every field read (``removed`` must be empty: see below).

        Raises:
            SimulationError: a car was removed (a ring of ContinuousRouter cars keeps a fixed
                population).
        """
        if removed:
            raise SimulationError(
                f"k.vehicle.remove({', '.join(map(repr, removed))}) on a ring "
                "whose cars all use ContinuousRouter: flowrun keeps those cars as a fixed "
                "population, so the run cannot go on; remove no car there, or give a "
                "vehicle type another router (the general path, where cars come and go)"
            )
        fast, ids = self.fast, self.table.ids
        n = len(ids)
        speed = np.fromiter(map(fast.get_speed, ids), np.float64, n)
        if self.multi_lane:
            self._lane_index = np.array(list(map(self.api.vehicle.getLaneIndex, ids)), np.int64)
        if self.read_xy_each_step:
            # flattened first: numpy would otherwise inspect every (x, y) tuple's shape
            xy = np.array(list(_flatten(map(fast.get_position, ids))), dtype=np.float64)
            self._x, self._y = xy[0::2], xy[1::2]
        odometer = np.fromiter(map(fast.get_distance, ids), np.float64, n)
        unwrapped = self._start_position + odometer
        position = np.mod(unwrapped, self.spec.length)
        if not self._uniform_speed:
            self._speed_limit = self._edge_speeds[self.ring_edges.index(position)]
        if self._any_continuous:
            self._check_routes(odometer, position)
        if self.multi_lane:
            leader, follower, headway = leaders_on_ring(
                position, self._lane_index, self.table.lengths, self.spec.length
            )
            complete = False
        else:
            leader, follower, headway = self._following.compute(unwrapped)
            complete = self._following.complete
        near = neighbours(speed, leader, follower, headway, complete=complete)
        prev = self.last
        self.last = RingState(
            speed, speed if first or prev is None else prev.speed, self.dt, position,
            self._lane_index, self._x, self._y, odometer, self._speed_limit, self._on_internal,
            leader, follower, headway, near.tailway, near.leader_speed, near.follower_speed,
            near.follower_headway, self.ring_edges,
        )  # fmt: skip
        return self.last

    def route(self, vk: Any) -> None:
        """Nothing: ContinuousRouter runs during :meth:`read`."""

    def _check_routes(self, odometer: FloatArray, position: FloatArray) -> None:
        """ContinuousRouter, checked only as often as needed.

        No car can reach its route's last edge sooner than its remaining distance divided by
        a bound on the distance per step (twice the fastest speed limit or vehicle maximum);
        until then the check is skipped.
        """
        if self._reroute_wait:
            self._reroute_wait -= 1
            return
        slack = self._next_reroute - odometer
        if slack.min() <= 0.0:
            self._reroute(odometer, position)
            slack = self._next_reroute - odometer
        nearest = float(slack.min())
        wait = nearest / self._max_step_distance
        self._reroute_wait = int(wait) if wait < 1e9 else 10**9

    def _reroute(self, odometer: FloatArray, position: FloatArray) -> None:
        """ContinuousRouter: a car that reached its route's last edge gets the next loop."""
        due = np.flatnonzero(odometer >= self._next_reroute)
        for i in due.tolist():
            vid = self.table.ids[i]
            edge = self.api.vehicle.getRoadID(vid)  # SUMO's own view at the boundary
            if edge not in self.spec.routes:
                continue
            self.api.vehicle.setRoute(vid, list(self.spec.routes[edge]))
            here = np.array([self._edge_pos[edge]])
            ahead = self._distance_to_route_end(here, position[i : i + 1])
            self._next_reroute[i] = odometer[i] + float(ahead[0])

    def route_chosen(self, row: int, route: Sequence[str]) -> None:
        """A car given a route by ``choose_routes``: that route is not looped."""
        self._next_reroute[row] = np.inf

    def resync(self) -> None:
        """Nothing to check: a ring's population is fixed (a teleport that took a car off
        fails at its next read)."""
