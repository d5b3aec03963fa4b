"""The vehicle kernel on open networks: who is on the road, where, and who follows whom.

A mixin of :class:`~flowrun.kernel.vehicle.VehicleKernel`. Each step SUMO's departed/arrived
lists update the population (:meth:`OpenRoadReads._follow_population`); speeds are read at
once, and each car's lane and position, map coordinates and leaders when first asked in a step
(on :class:`~flowrun.kernel.vehicle.OpenVehicleKernel`). The closed ring never comes here.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from itertools import chain
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from flowrun.kernel.lane_graph import LaneGraph
from flowrun.kernel.open_road import Following

if TYPE_CHECKING:
    from flowrun.kernel.lanes import LaneTable
    from flowrun.kernel.population import Population
    from flowrun.kernel.sumo import FastCalls
    from flowrun.networks.base import NetworkSpec

_flatten = chain.from_iterable

NO_ROWS = np.zeros(0, dtype=np.int64)
NEVER = -(10**18)  # a clock no step has

#: the per-step arrays an open network finds when first read (see ``_find_following``)
FOLLOWING = frozenset(
    ("leader", "follower", "headway", "tailway", "leader_speed", "follower_speed",
     "follower_headway")
)  # fmt: skip
#: where each car is: read when first asked in a step on an open network (``_read_place``)
PLACE = frozenset(("_lane_key", "_lane_pos"))
#: what follows from where each car is: derived when first asked (``_derive_place``)
WHERE = frozenset(("lanes", "position", "speed_limit", "on_internal"))
XY = frozenset(("x", "y"))
PLACE_AND_FOLLOWING = FOLLOWING | PLACE | WHERE | XY


class OpenRoadReads:
    """Population, places and followers of the cars on an open network (see module doc)."""

    LAZY_FOLLOWING: ClassVar[bool]
    table: Population
    spec: NetworkSpec
    api: Any
    dt: float
    rng: np.random.Generator
    read_xy: bool
    group_routers: Any
    departed_ids: list[str]
    arrived_ids: list[str]
    speed: np.ndarray
    prev_speed: np.ndarray
    lanes: np.ndarray
    position: np.ndarray
    speed_limit: np.ndarray
    on_internal: np.ndarray
    x: np.ndarray
    y: np.ndarray
    leader: np.ndarray
    follower: np.ndarray
    headway: np.ndarray
    tailway: np.ndarray
    leader_speed: np.ndarray
    follower_speed: np.ndarray
    follower_headway: np.ndarray
    accel_cmd: np.ndarray
    last_cmd: np.ndarray
    _no_cmd: np.ndarray
    _all: slice
    _fast: FastCalls
    _lanes: LaneTable | None
    _following_open: Following | None
    _route_of: dict[str, tuple[str, ...]]
    _route_end: np.ndarray
    _pending_removal: list[str]
    _resync: bool
    _flow_counts: deque[tuple[int, int]]
    _version: int
    _speed_now: np.ndarray
    _new_rows: np.ndarray
    _odometer: np.ndarray | None
    _stale_edges: bool
    _pending: bool
    _place_pending: bool
    _where_pending: bool
    _xy_pending: bool
    _lane_key: np.ndarray
    _lane_pos: np.ndarray
    _prev_key: np.ndarray
    _prev_pos: np.ndarray
    _place_ms: int
    _now_ms: int
    _step_ms: int

    def _update_open(self, first: bool) -> np.ndarray:
        """Any network: follow the population, read speeds; where each car is (lane,
        position, map coordinates) and who follows whom are read when first asked."""
        self._now_ms = round(self._fast.sim_time() * 1000)
        self._follow_population(first)
        self.prev_speed = self.speed
        fast, pop = self._fast, self.table
        ids = pop.ids
        speed = np.fromiter(map(fast.get_speed, ids), np.float64, len(ids))
        self._speed_now = speed
        if self._new_rows.size:  # a car that just entered has no speed before: no acceleration
            self.prev_speed = self.prev_speed.copy()
            self.prev_speed[self._new_rows] = speed[self._new_rows]
            self._new_rows = NO_ROWS
        self._odometer = None  # read when someone asks (recording, get_distance)
        self._stale_edges = True
        # A step nobody asks about (the first of two sims per env step with SUMO-driven
        # humans) reads nothing more; the look-ahead of ContinuousRouter needs the lanes now.
        self._pending = True
        routers = self.group_routers
        if self.LAZY_FOLLOWING and not pop.any_continuous and not routers:
            d = self.__dict__
            for name in PLACE_AND_FOLLOWING if self.read_xy else PLACE_AND_FOLLOWING - XY:
                d.pop(name, None)
            self._place_pending = True
            self._xy_pending = self.read_xy
        else:
            self._read_place()
            self._derive_place()
            if self.read_xy:
                self._read_xy()
            if pop.any_continuous:  # before the look-ahead, which follows the new route
                self._route_continuously(self._lanes.edge_index[self._lane_key])  # type: ignore[union-attr]
            if routers:  # routers of whole groups (e.g. MinicityRouter), also before it
                routers.step(self, self._lanes)
            if self.LAZY_FOLLOWING:
                for name in FOLLOWING:
                    self.__dict__.pop(name, None)
            else:
                self._find_following()
        return speed

    def _read_place(self) -> None:
        """Every car's lane and position on it (this step); what follows from them is
        derived when first asked (:meth:`_derive_place`).

        The lane id is asked of SUMO only for the cars that may have changed lanes. Where the
        places of the step just before were read (by SUMO's clock: after a step nobody asked
        about, or one taken around the kernel, all are read), a car on the only lane of its
        edge whose position grew by exactly ``speed * dt`` (SUMO's Euler step, bit for bit)
        is on the same lane: had it passed onto the next lane, its position would have lost
        that lane's length, and it cannot change lanes sideways. Any other car (entered, on a
        multi-lane edge, crossing a lane's end, teleported, moved by a command, or any step
        method but Euler) is read.
        """
        self._place_pending = False
        fast, lanes, ids = self._fast, self._lanes, self.table.ids
        assert lanes is not None
        n = len(ids)
        pos = np.fromiter(map(fast.get_lane_position, ids), np.float64, n)
        prev_key = self._prev_key
        if self._place_ms == self._now_ms - self._step_ms and prev_key.size == n:
            # (a new row's key is -1: alone[-1] is False)
            same = (pos == self._prev_pos + self._speed_now * self.dt) & lanes.alone[prev_key]
            keys = prev_key.copy()
            moved = (~same).nonzero()[0].tolist()  # (np.flatnonzero: a Python layer)
            if moved:
                get_lane = fast.get_lane_id
                keys[moved] = lanes.keys([get_lane(ids[r]) for r in moved])
        else:
            keys = lanes.keys(list(map(fast.get_lane_id, ids)))
        self._lane_key, self._lane_pos = keys, pos
        self._prev_key, self._prev_pos = keys, pos.copy()  # (lane_pos is the caller's array)
        self._place_ms = self._now_ms
        self._where_pending = True

    def _derive_place(self) -> None:
        """Lane index, network position, speed limit and internal-edge flag of every car,
        from its lane and position on it (this step's, read by :meth:`_read_place`)."""
        self._where_pending = False
        lanes, keys, lane_pos = self._lanes, self._lane_key, self._lane_pos
        assert lanes is not None
        self.lanes = lanes.lane_index[keys]
        self.position = lanes.start[keys] + lane_pos
        self.speed_limit = lanes.speed_limit[keys]
        self.on_internal = lanes.internal[keys]

    def _read_xy(self) -> None:
        """Every car's map coordinates (this step)."""
        self._xy_pending = False
        xy = np.array(list(_flatten(map(self._fast.get_position, self.table.ids))), np.float64)
        self.x, self.y = xy[0::2], xy[1::2]

    def _read_pending(self) -> None:
        """Read now what this step has not read yet (before a car leaves mid-step)."""
        if self.__dict__.get("_place_pending"):
            self._read_place()
        if self.__dict__.get("_xy_pending"):
            self._read_xy()
        if self.__dict__.get("_pending") and self.LAZY_FOLLOWING and "leader" not in self.__dict__:
            self._find_following()

    def _find_following(self) -> None:
        """Leader, follower, headway, tailway and neighbour speeds of the current step."""
        self._pending = False
        assert self._following_open is not None
        leader, follower, headway, tailway = self._following_open.compute(
            self.table, self._lane_key, self._lane_pos, self._route_of
        )
        speed = self.speed
        has_lead, has_fol = leader >= 0, follower >= 0
        self.leader, self.follower, self.headway, self.tailway = leader, follower, headway, tailway
        self.leader_speed = np.where(has_lead, speed[np.where(has_lead, leader, 0)], speed)
        self.follower_speed = np.where(has_fol, speed[np.where(has_fol, follower, 0)], speed)
        self.follower_headway = tailway

    def _attach_open(self, api: Any, lanes: LaneTable) -> None:
        self._lanes = lanes
        self._following_open = Following.of(api, LaneGraph(lanes), lanes.edge_pos)
        self._route_of = {}
        self._route_end = np.full(self.table.size, -1, dtype=np.int64)
        self._pending_removal = []
        self._flow_counts.clear()
        self._version = -1  # rebuild the per-row arrays at the first update

    def _follow_population(self, first: bool) -> None:
        """Add the cars SUMO inserted, drop those that arrived (or were removed)."""
        fast, pop = self._fast, self.table
        if first:
            # Flow's reset counts no departure, but a car SUMO inserted during the reset's two
            # steps (an inflow from 1 s at 1 s steps, a template's <flow begin="0">) is on the
            # road: it joins, as in Flow's update
            entered = [vid for vid in self.api.vehicle.getIDList() if vid not in pop]
            departed: list[str] = []
            arrived: list[str] = []
        else:
            entered = departed = list(fast.departed_ids())
            arrived = list(fast.arrived_ids())
        arrived += self._pending_removal
        self._pending_removal = []
        if self._resync:  # teleports can take cars off the road: ask SUMO who is there
            self._resync = False
            now = self.api.vehicle.getIDList()
            present = set(now)
            arrived = [v for v in pop.ids if v not in present]
            entered = departed = [v for v in now if v not in pop]
        self.departed_ids, self.arrived_ids = departed, arrived
        self._flow_counts.append((len(departed), len(arrived)))
        if not entered and not arrived and self._version == pop.version:
            return
        v = self.api.vehicle
        groups = [pop.class_index(v.getTypeID(vid)) for vid in entered]
        old_route_end = self._route_end
        old_prev = self.speed
        src = pop.change(arrived, entered, groups)
        for vid in arrived:
            self._route_of.pop(vid, None)
        for vid, g in zip(entered, groups, strict=True):
            if g != pop.foreign:  # Flow's modes hold from a car's first step
                c = pop.classes[g]
                v.setSpeedMode(vid, c.speed_mode)
                v.setLaneChangeMode(vid, c.lane_change_mode)
        if src is None:  # nothing changed (e.g. a removed car was never seen)
            src = np.arange(pop.size)
        self._resize(src, old_route_end, old_prev)
        self._version = pop.version

    def _resize(self, src: np.ndarray, old_route_end: np.ndarray, old_speed: np.ndarray) -> None:
        """Carry per-row state that outlives a step over to the new rows (``src``: each new
        row's row before the change, -1 for a car that just entered)."""
        pop, lanes = self.table, self._lanes
        assert lanes is not None
        n = pop.size
        kept = src >= 0
        carried = np.where(kept, src, 0)
        self._route_end = np.where(kept, old_route_end[carried] if old_route_end.size else -1, -1)
        if self._prev_key.size == old_route_end.size:  # the last places, row by row
            old_key, old_pos = self._prev_key, self._prev_pos
            self._prev_key = np.where(kept, old_key[carried], -1) if old_key.size else src
            self._prev_pos = np.where(kept, old_pos[carried], np.nan) if old_pos.size else \
                np.full(n, np.nan)  # fmt: skip
        else:
            self._place_ms = NEVER
        self.speed = np.where(kept, old_speed[carried] if old_speed.size else 0.0, 0.0)
        self.last_cmd = np.full(n, np.nan)
        self._no_cmd = np.full(n, np.nan)
        self.accel_cmd = self._no_cmd.copy()
        self._all = slice(0, n)
        self._new_rows = (~kept).nonzero()[0]
        rows = (~kept | (self._route_end < 0)).nonzero()[0]
        get_route = self.api.vehicle.getRoute
        for r in rows.tolist():
            vid = pop.ids[r]
            route = tuple(get_route(vid))
            self._route_of[vid] = route
            self._route_end[r] = lanes.edge_pos.get(route[-1], -1) if route else -1

    def _route_continuously(self, edge_index: np.ndarray) -> None:
        """ContinuousRouter on any network: a car on its route's last edge gets a new route
        starting on that edge (drawn from the edge's route choices)."""
        due = np.flatnonzero(self.table.continuous & (edge_index == self._route_end))
        if not due.size:
            return
        assert self._lanes is not None
        names = self._lanes.edge_names
        for r in due.tolist():
            edge = names[int(edge_index[r])]
            choices = self.spec.choices(edge)
            if not choices:
                self._route_end[r] = -1
                continue
            if len(choices) == 1:
                route = choices[0][0]
            else:
                probs = np.array([p for _, p in choices], dtype=np.float64)
                route = choices[int(self.rng.choice(len(choices), p=probs / probs.sum()))][0]
            self.reroute_now([r], [route])

    def reroute_now(self, rows: Sequence[int], routes: Sequence[Sequence[str]]) -> None:
        """Give the cars of ``rows`` new routes at once (a router during the update)."""
        assert self._lanes is not None
        for r, route in zip(rows, routes, strict=True):
            vid = self.table.ids[r]
            self.api.vehicle.setRoute(vid, list(route))
            self._route_of[vid] = tuple(route)
            self._route_end[r] = self._lanes.edge_pos.get(route[-1], -1)

    def resync(self) -> None:
        """Check the population against SUMO's vehicle list at the next update (after a
        teleport, which the departed/arrived lists do not report)."""
        self._resync = True
