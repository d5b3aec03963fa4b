"""Vehicle state, read once per step into arrays, and the commands sent back to SUMO.

Every getter serves the snapshot taken by :meth:`VehicleKernel.update`; none of them calls
SUMO. Commands (:meth:`apply_acceleration`, ...) are buffered and sent in :meth:`send_commands`
just before the simulation step.
"""

from __future__ import annotations

from collections import deque
from itertools import chain
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from flowrun.errors import SimulationError
from flowrun.kernel.geometry import LaneGeometry, RingEdges, RingPlacement
from flowrun.kernel.lanes import LaneTable
from flowrun.kernel.open_road import Following
from flowrun.kernel.population import Population, VehicleTable
from flowrun.kernel.snapshot import RingFollowing, leaders_on_ring
from flowrun.kernel.sumo import FastCalls
from flowrun.kernel.vehicle_api import FlowVehicleGetters
from flowrun.kernel.vehicle_commands import VehicleCommands
from flowrun.kernel.vehicle_open import (
    FOLLOWING,
    NEVER,
    NO_ROWS,
    PLACE,
    WHERE,
    XY,
    OpenRoadReads,
)
from flowrun.networks.base import NetworkSpec
from flowrun.types import CarFollowingInputs

_flatten = chain.from_iterable


def ring_fast_path(spec: NetworkSpec, initial: VehicleTable) -> bool:
    """Whether the closed-ring shortcuts hold: a ring whose cars all circle forever
    (``ContinuousRouter``), so nobody enters or leaves. A car without it leaves the ring at
    its route's end, as in Flow, and the general path follows it."""
    return spec.closed and all(initial.classes[g].continuous for g in set(initial.group.tolist()))


class VehicleKernel(VehicleCommands, FlowVehicleGetters, OpenRoadReads):
    """Flow's ``k.vehicle``: per-step vehicle state and commands.

    Per-vehicle state is held in compact arrays, one row per vehicle in the network now
    (``table`` is the :class:`Population`: ids, groups, lengths, ... of the same rows). On a
    closed ring with no departures the rows never change and leaders come from one sort
    around the loop; on any other network the population follows SUMO's departed / arrived
    lists and leaders are found per lane and across junctions (:mod:`open_road`).

    Args:
        initial: the vehicles placed at the start of the episode and every group's facts.
        spec: the network the vehicles drive on.
        dt: simulation step, s.
        rng: the generator route choices are drawn from (``ContinuousRouter``).
    """

    #: find who follows whom only when first asked in a step (see OpenVehicleKernel)
    LAZY_FOLLOWING: ClassVar[bool] = False

    def __init__(
        self,
        initial: VehicleTable,
        spec: NetworkSpec,
        dt: float,
        rng: np.random.Generator | None = None,
    ) -> None:
        self._pending = False  # the following arrays of this step are still to be found
        self._place_pending = False  # lanes and positions of this step are still to be read
        self._where_pending = False  # what follows from them is still to be derived
        self._xy_pending = False  # map coordinates of this step are still to be read
        self.initial = initial
        self.table = Population(initial.classes)
        self.table.add(initial.ids, initial.group.tolist())
        self.spec = spec
        self.dt = dt
        self.rng = rng if rng is not None else np.random.default_rng(0)
        #: routers of whole groups, run at each update (set by the kernel's owner)
        self.group_routers: Any = None
        self.api: Any = None
        self.read_xy = True
        self.ring_path = ring_fast_path(spec, initial)
        n = initial.size
        self._all = slice(0, n)
        self._edges_cache: list[str] | None = [""] * n
        self._lane_pos = np.zeros(n)
        self._leader_ids: tuple[np.ndarray | None, list[str]] = (None, [])
        self._stale_edges = False
        self._next_reroute = np.full(n, np.inf)
        self.leader_speed = np.zeros(n)
        self.follower_speed = np.zeros(n)
        self.follower_headway = np.full(n, np.inf)
        self.lanes = np.zeros(n, dtype=np.int64)
        self.position = np.zeros(n)
        self.speed = np.zeros(n)
        self.prev_speed = np.zeros(n)
        self._accel_real: np.ndarray | None = np.zeros(n)
        self._reroute_wait = 0
        self._max_step_distance = 1.0
        self._no_cmd = np.full(n, np.nan)
        self.accel_cmd = self._no_cmd.copy()
        self.last_cmd = np.full(n, np.nan)
        self.headway = np.full(n, np.inf)
        self.leader = np.full(n, -1, dtype=np.int64)
        self.follower = np.full(n, -1, dtype=np.int64)
        self._odometer: np.ndarray | None = np.zeros(n)
        self.x = np.zeros(n)
        self.y = np.zeros(n)
        self.speed_limit = np.full(n, np.inf)
        self._lane_change: dict[int, int] = {}
        self._routes: dict[int, list[str]] = {}
        self._edge_by_id = {e.id: e for e in spec.edges}
        self._multi_lane = any(e.lanes > 1 for e in spec.edges)
        self.tailway = np.full(n, np.inf)
        self.on_internal = np.zeros(n, dtype=bool)
        self._lane_key = np.zeros(n, dtype=np.int64)
        self._lanes: LaneTable | None = None
        #: SUMO's clock (ms) at this update (open networks), the clock of the step whose lanes
        #: and positions ``_prev_key`` / ``_prev_pos`` hold (rows as now), the step length
        #: (ms) and this step's speeds: see ``_read_place``
        self._now_ms = 0
        self._place_ms = NEVER
        self._step_ms = round(dt * 1000)
        self._prev_key = NO_ROWS
        self._prev_pos = np.zeros(0)
        self._speed_now = np.zeros(0)
        self._following_open: Following | None = None
        #: every car's route by id (from SUMO when it enters, kept when flowrun reroutes it)
        self._route_of: dict[str, tuple[str, ...]] = {}
        self._version = self.table.version
        self._route_end = np.full(n, -1, dtype=np.int64)
        self._pending_removal: list[str] = []
        self._resync = False
        self._new_rows = NO_ROWS
        self._observed: dict[str, None] = {}
        self.departed_ids: list[str] = []
        self.arrived_ids: list[str] = []
        self._flow_counts: deque[tuple[int, int]] = deque(maxlen=100_000)

    # ------------------------------------------------------------------ reading
    def attach(self, api: Any, lanes: LaneTable | None = None) -> None:
        """Bind to a freshly started simulation (``libsumo`` or ``traci`` module)."""
        self.api = api
        self._fast = FastCalls.of(api)
        if not self.ring_path:
            self._attach_open(api, lanes or LaneTable.read(api, self.spec))
            return
        spec = self.spec
        self._edge_ids = [e.id for e in spec.edges]
        self._edge_pos = {e: i for i, e in enumerate(self._edge_ids)}
        self._starts = np.array([spec.edge_starts[e] for e in self._edge_ids])
        self._ring_edges = RingEdges(self._starts, self._edge_ids)
        self._edge_speeds = np.array([e.speed for e in spec.edges])
        self._uniform_speed = bool(np.all(self._edge_speeds == self._edge_speeds[0]))
        start_idx = np.array(
            [self._edge_pos.get(e, 0) for e in self.initial.start_edges], dtype=np.int64
        )
        self._start_position = self._starts[start_idx] + np.array(self.initial.start_lane_pos)
        self._following = RingFollowing(self.table.lengths, spec.length)
        self._any_continuous = bool(self.table.continuous.any())
        self.speed_limit = np.full(self.table.size, self._edge_speeds[0])
        # A route runs once around the ring from its first edge, so its last edge is the one
        # before: ContinuousRouter gives a car its next loop when its odometer reaches it.
        self._next_reroute = np.where(
            self.table.continuous,
            self._distance_to_route_end(start_idx, self._start_position),
            np.inf,
        )
        fastest = max(float(self._edge_speeds.max()), float(self.table.max_speeds.max(initial=0.0)))
        self._max_step_distance = 2.0 * fastest * self.dt + 1e-9
        self._reroute_wait = 0
        self._stale_edges = True

    def placement(self) -> RingPlacement:
        """Edges, lane positions and map coordinates of ring positions, for batches of steps,
        on the network of this episode (closed networks; reads the lane shapes once)."""
        lane = self.api.lane
        edges = self.spec.edges
        geometry = LaneGeometry(
            [[lane.getShape(f"{e.id}_{i}") for i in range(e.lanes)] for e in edges],
            [[lane.getLength(f"{e.id}_{i}") for i in range(e.lanes)] for e in edges],
        )
        return RingPlacement(self._ring_edges, geometry)

    def _distance_to_route_end(self, edge_idx: np.ndarray, position: np.ndarray) -> np.ndarray:
        last = np.mod(edge_idx - 1, len(self._edge_ids))
        return np.mod(self._starts[last] - position, self.spec.length)

    def update(self, first: bool = False) -> None:
        """Read every vehicle's state from SUMO into the arrays (plain getters, one pass).

        On a closed ring two getters per car suffice: speed and odometer. The ring position is
        the entry position plus the odometer (equal to SUMO's edge offset + lane position to
        ~1e-13 m); edges and lane positions follow from it when someone asks.
        """
        fast = self._fast
        self._accel_real = None
        if not self.ring_path:
            speed = self._update_open(first)
        else:
            if self._pending_removal:
                raise SimulationError(
                    f"k.vehicle.remove({', '.join(map(repr, self._pending_removal))}) on a ring "
                    "whose cars all use ContinuousRouter: flowrun keeps those cars as a fixed "
                    "population, so the run cannot go on; remove no car there, or give a "
                    "vehicle type another router (the general path, where cars come and go)"
                )
            ids = self.table.ids
            self.prev_speed = self.speed
            n = len(ids)
            speed = np.fromiter(map(fast.get_speed, ids), np.float64, n)
            if self._multi_lane:
                self.lanes = np.array(list(map(self.api.vehicle.getLaneIndex, ids)), np.int64)
            if self.read_xy:
                # flattened first: numpy would otherwise inspect every (x, y) tuple's shape
                xy = np.array(list(_flatten(map(fast.get_position, ids))), dtype=np.float64)
                self.x, self.y = xy[0::2], xy[1::2]
            self._odometer = odometer = np.fromiter(map(fast.get_distance, ids), np.float64, n)
            unwrapped = self._start_position + odometer
            self.position = np.mod(unwrapped, self.spec.length)
            self._stale_edges = True
            if not self._uniform_speed:
                self.speed_limit = self._edge_speeds[self._ring_edges.index(self.position)]
            if self._any_continuous:
                self._check_routes()
            if self._multi_lane:
                self.leader, self.follower, self.headway = leaders_on_ring(
                    self.position, self.lanes, self.table.lengths, self.spec.length
                )
            else:
                self.leader, self.follower, self.headway = self._following.compute(unwrapped)
        if first:
            self.prev_speed = speed
        self.speed = speed
        if not self.ring_path:
            pass  # found when first asked (see _find_following)
        elif not self._multi_lane and self._following.complete:
            self.leader_speed = speed[self.leader]
            self.follower_speed = speed[self.follower]
            self.follower_headway = self.headway[self.follower]
        else:
            has_lead, has_fol = self.leader >= 0, self.follower >= 0
            self.leader_speed = np.where(has_lead, speed[self.leader], speed)
            self.follower_speed = np.where(has_fol, speed[self.follower], speed)
            self.follower_headway = np.where(has_fol, self.headway[self.follower], np.inf)
        if self.ring_path:
            self.tailway = self.follower_headway

    @property
    def edge_index(self) -> np.ndarray | None:
        """Every car's edge as an index into :attr:`edge_names` (``None`` on the ring's
        fast path, which has no lane table)."""
        if self._lanes is None:
            return None
        return self._lanes.edge_index[self._lane_key]

    @property
    def edge_names(self) -> list[str]:
        """The network's edge ids, junction-internal ones included, as :attr:`edge_index`
        counts them (empty on the ring's fast path)."""
        return [] if self._lanes is None else self._lanes.edge_names

    @property
    def multi_lane(self) -> bool:
        """Whether any edge of the network has more than one lane."""
        return self._multi_lane

    @property
    def odometer(self) -> np.ndarray:
        """Distance every car has driven since it entered, m (SUMO's ``getDistance``)."""
        if self._odometer is None:
            get = self._fast.get_distance
            ids = self.table.ids
            self._odometer = np.fromiter(map(get, ids), np.float64, len(ids))
        return self._odometer

    @property
    def accel_real(self) -> np.ndarray:
        """Acceleration realised over the last step, m/s^2 (computed when first asked)."""
        if self._accel_real is None:
            self._accel_real = (self.speed - self.prev_speed) / self.dt
        return self._accel_real

    def _derive_edges(self) -> None:
        if self._stale_edges and not self.ring_path:
            assert self._lanes is not None
            names = self._lanes.edge_names
            self._edges_cache = [names[e] for e in self._lanes.edge_index[self._lane_key].tolist()]
            self._stale_edges = False
        elif self._stale_edges:
            idx, self._lane_pos = self._ring_edges.locate(self.position)
            self._edges_cache = self._ring_edges.edge_names(idx)
            self._stale_edges = False

    @property
    def lane_pos(self) -> np.ndarray:
        """Position of every vehicle on its lane, m."""
        if self.ring_path:  # derived from the ring position with the edges
            self._derive_edges()
        return self._lane_pos

    @property
    def edges(self) -> list[str]:
        """Edge id of every vehicle (derived from the ring position on closed networks)."""
        self._derive_edges()
        assert self._edges_cache is not None
        return self._edges_cache

    def _check_routes(self) -> None:
        """ContinuousRouter, checked only as often as needed.

        No car can reach its route's last edge sooner than its remaining distance divided by
        a bound on the distance per step (twice the fastest speed limit or vehicle maximum);
        until then the check is skipped.
        """
        if self._reroute_wait:
            self._reroute_wait -= 1
            return
        slack = self._next_reroute - self.odometer
        if slack.min() <= 0.0:
            self._reroute()
            slack = self._next_reroute - self.odometer
        nearest = float(slack.min())
        wait = nearest / self._max_step_distance
        self._reroute_wait = int(wait) if wait < 1e9 else 10**9

    def _reroute(self) -> None:
        """ContinuousRouter: a car that reached its route's last edge gets the next loop."""
        due = np.flatnonzero(self.odometer >= self._next_reroute)
        for i in due.tolist():
            vid = self.table.ids[i]
            edge = self.api.vehicle.getRoadID(vid)  # SUMO's own view at the boundary
            if edge not in self.spec.routes:
                continue
            self.api.vehicle.setRoute(vid, list(self.spec.routes[edge]))
            here = np.array([self._edge_pos[edge]])
            ahead = self._distance_to_route_end(here, self.position[i : i + 1])
            self._next_reroute[i] = self.odometer[i] + float(ahead[0])

    def remove(self, veh_id: str) -> None:
        """Take a vehicle out of the simulation (it leaves the arrays at the next step)."""
        if self.LAZY_FOLLOWING:
            self._read_pending()  # this step's state, read while the car is still there
        self.api.vehicle.remove(veh_id)
        self._pending_removal.append(veh_id)

    # ------------------------------------------------------------------ controller inputs
    def inputs(self, idx: np.ndarray | slice, time: float) -> CarFollowingInputs:
        """The state a car-following controller needs, for the vehicles ``idx``."""
        if isinstance(idx, slice) and idx == self._all:  # one group drives every car
            return CarFollowingInputs(
                self.speed, self.headway, self.leader_speed, self.follower_headway,
                self.follower_speed, self.speed_limit, self.dt, time,
                self.table.accels, self.table.decels, self.table.lengths,
            )  # fmt: skip
        return CarFollowingInputs(
            speed=self.speed[idx],
            headway=self.headway[idx],
            leader_speed=self.leader_speed[idx],
            follower_headway=self.follower_headway[idx],
            follower_speed=self.follower_speed[idx],
            speed_limit=self.speed_limit[idx],
            dt=self.dt,
            time=time,
            max_accel=self.table.accels[idx],
            max_decel=self.table.decels[idx],
            length=self.table.lengths[idx],
        )


class OpenVehicleKernel(VehicleKernel):
    """The vehicle kernel on a network other than a closed ring: the same kernel, with the
    arrays of who follows whom found when first read in a step.

    (A class of its own because a ``__getattr__`` slows every attribute read of its class in
    CPython; the ring's hot path reads the kernel's attributes many times per step.)
    """

    LAZY_FOLLOWING: ClassVar[bool] = True

    if not TYPE_CHECKING:  # for mypy these stay plain typed attributes

        def __getattr__(self, name: str) -> Any:
            # Reached only for an attribute that is not set: on an open network, the arrays
            # of who follows whom are found when first read in a step, so a step nobody
            # asks (the first of two sims per env step with SUMO-driven humans) costs
            # nothing. The ring sets them every step and never comes here.
            d = self.__dict__
            if name in PLACE and d.get("_place_pending"):
                self._read_place()
                return d[name]
            if name in WHERE and (d.get("_place_pending") or d.get("_where_pending")):
                self._derive_place()  # reads the places first if they are pending
                return d[name]
            if name in XY and d.get("_xy_pending"):
                self._read_xy()
                return d[name]
            if name in FOLLOWING and d.get("_pending"):
                self._find_following()
                return d[name]
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
