"""The open road's reader: who is on the road, where, and who follows whom.

Each step SUMO's departed/arrived lists update the population; speeds are read at once and
make the step's :class:`~flowrun.kernel.state.OpenState`, whose other fields (each car's lane
and position, map coordinates, leaders) this reader reads from SUMO when the state is first
asked for them. Leaders come from the lane graph plus SUMO's ``getLeader``
(:class:`~flowrun.kernel.open_road.Following`).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from itertools import chain
from typing import TYPE_CHECKING, Any

import numpy as np

from flowrun.kernel.following import SMALL, Neighbours, neighbours
from flowrun.kernel.lane_graph import LaneGraph
from flowrun.kernel.open_road import Following
from flowrun.kernel.state import OpenState
from flowrun.types import FloatArray, IntArray

if TYPE_CHECKING:
    from flowrun.kernel.lanes import LaneTable
    from flowrun.kernel.population import Population
    from flowrun.kernel.sumo import FastCalls
    from flowrun.networks.base import NetworkSpec

_flatten = chain.from_iterable

NO_ROWS = np.zeros(0, dtype=np.int64)
NO_ROWS.flags.writeable = False
NEVER = -(10**18)  # a clock no step has


class OpenReader:
    """Reads the cars of any network but the closed ring (see the module doc).

    Args:
        table: the population (changed in place as cars come and go).
        spec: the network.
        dt: simulation step, s.
        rng: the generator route choices are drawn from (``ContinuousRouter``).
        api: ``libsumo`` or ``traci``; fast: its compiled getters.
        lanes: the network's lanes as SUMO built them.

    Attributes:
        read_xy_each_step: map coordinates are read at every update (recording).
        group_routers: routers of whole groups, run at each update (``GroupRouters``).
        departed_ids, arrived_ids: the cars that entered / left in the last step.
        flow_counts: (entered, left) of the recent steps.
        rows_changed: the last update changed the population's rows.
        route_end: every car's route's last edge as a lane-table edge index (-1: unknown).
    """

    def __init__(self, table: Population, spec: NetworkSpec, dt: float, rng: np.random.Generator,
                 api: Any, fast: FastCalls, lanes: LaneTable) -> None:  # fmt: skip
        self.table, self.spec, self.dt, self.rng = table, spec, dt, rng
        self.api, self.fast, self.lanes = api, fast, lanes
        self.read_xy_each_step = True
        self.group_routers: Any = None
        self._following = Following.of(api, LaneGraph(lanes), lanes.edge_pos)
        #: every car's route by id (from SUMO when it enters, kept when flowrun reroutes it)
        self.route_of: dict[str, tuple[str, ...]] = {}
        self.route_end = np.full(table.size, -1, dtype=np.int64)
        self.departed_ids: list[str] = []
        self.arrived_ids: list[str] = []
        self.flow_counts: deque[tuple[int, int]] = deque(maxlen=100_000)
        self.rows_changed = False
        #: the state of the last update
        self.last: OpenState | None = None
        self._resync = False
        self._version = -1  # rebuild the per-row arrays at the first update
        #: SUMO's clock (ms) at this update, the clock of the step whose lanes and positions
        #: ``_prev_key`` / ``_prev_pos`` hold (rows as now), the step length (ms) and this
        #: step's speeds: see :meth:`read_place`
        self._now_ms = 0
        self._place_ms = NEVER
        self._step_ms = round(dt * 1000)
        self._prev_key = NO_ROWS
        self._prev_pos = np.zeros(0)
        #: the last read's lane keys and positions as handed out and as lists, when it was of
        #: few cars and every car had been read the step before (``None``: not kept)
        self._lists: tuple[IntArray, FloatArray, list[int], list[float]] | None = None
        #: ContinuousRouter must look at the cars again (see :meth:`route`)
        self._route_due = True
        #: lane keys and the lane table's columns at them that a state looked up
        self._columns: tuple[IntArray, dict[str, Any]] = (NO_ROWS, {})

    def read(self, first: bool, removed: list[str]) -> OpenState:
        """This step's state: follow the population (``removed``: the cars taken out since the
        last update), read the speeds; the rest is read when first asked."""
        fast = self.fast
        self._now_ms = round(fast.sim_time() * 1000)
        prev_speed = self.last.speed if self.last is not None else np.zeros(0)
        src = self._follow_population(first, removed)
        self.rows_changed = src is not None
        new_rows = NO_ROWS
        if src is not None:  # each row's speed before, 0 for a car that just entered
            kept = src >= 0
            carried = np.where(kept, src, 0)
            prev_speed = np.where(kept, prev_speed[carried] if prev_speed.size else 0.0, 0.0)
            new_rows = (~kept).nonzero()[0]
        ids = self.table.ids
        speed = np.fromiter(map(fast.get_speed, ids), np.float64, len(ids))
        if first:
            prev_speed = speed
        elif new_rows.size:  # a car that just entered has no speed before: no acceleration
            prev_speed[new_rows] = speed[new_rows]
        self.last = OpenState(speed, prev_speed, self.dt, self)
        return self.last

    def route(self, vk: Any) -> None:
        """ContinuousRouter and the routers of whole groups, on this step's lanes (``vk``:
        the kernel the routers ask). A step with neither reads nothing more."""
        routers = self.group_routers
        if not self.table.any_continuous and not routers:
            return
        state = self.last
        assert state is not None
        _ = state.lane_key  # the lanes and what follows, read before any car is rerouted
        if self.read_xy_each_step:
            _ = state.xy
        # before the look-ahead, which follows the new route; skipped while no car changed
        # lanes, no route's end changed and no car was due at the last check (none is now)
        if self.table.any_continuous and (self._route_due or self.rows_changed):
            self._route_continuously(state.edge_index)
        if routers:  # routers of whole groups (e.g. MinicityRouter), also before it
            routers.step(vk, self.lanes)

    # ------------------------------------------------------------------ reads when asked
    def read_place(self, speed: FloatArray) -> tuple[IntArray, FloatArray]:
        """Every car's lane key and position on it, this step.

        The lane id is asked of SUMO only for the cars that may have changed lanes. Where the
        places of the step just before were read (by SUMO's clock: after a step nobody asked
        about, or one taken around the kernel, all are read), a car on the only lane of its
        edge whose position grew by exactly ``speed * dt`` (SUMO's Euler step, bit for bit)
        is on the same lane: had it passed onto the next lane, its position would have lost
        that lane's length, and it cannot change lanes sideways. Any other car (entered, on a
        multi-lane edge, crossing a lane's end, teleported, moved by a command, or any step
        method but Euler) is read.
        """
        fast, lanes, ids = self.fast, self.lanes, self.table.ids
        n = len(ids)
        prev_key, lists = self._prev_key, self._lists
        self._lists = None
        if self._place_ms == self._now_ms - self._step_ms and prev_key.size == n:
            # (a new row's key is -1: alone[-1] is False)
            if n <= SMALL:  # the same test on lists: fewer numpy calls (a per-call cost)
                key_l, prev_l = lists[2:] if lists is not None else (
                    prev_key.tolist(), self._prev_pos.tolist())  # fmt: skip
                pos_l = list(map(fast.get_lane_position, ids))
                pos = np.array(pos_l, np.float64)
                dt, alone = self.dt, lanes.alone_l
                moved = [r for r, p, q, v, k in zip(range(n), pos_l, prev_l, speed.tolist(),
                                                    key_l, strict=True)
                         if not (p == q + v * dt and alone[k])]  # fmt: skip
            else:
                pos = np.fromiter(map(fast.get_lane_position, ids), np.float64, n)
                same = (pos == self._prev_pos + speed * self.dt) & lanes.alone[prev_key]
                moved = (~same).nonzero()[0].tolist()  # (np.flatnonzero: a Python layer)
            keys = prev_key  # every car on its lane: the last step's array (read-only)
            if moved:
                get_lane = fast.get_lane_id
                keys = prev_key.copy()
                keys[moved] = lanes.keys([get_lane(ids[r]) for r in moved])
                keys.flags.writeable = False
                self._route_due = True  # (a car may be on another edge)
            if n <= SMALL:
                self._lists = (keys, pos, keys.tolist() if moved else key_l, pos_l)
        else:
            pos = np.fromiter(map(fast.get_lane_position, ids), np.float64, n)
            keys = lanes.keys(list(map(fast.get_lane_id, ids)))
            keys.flags.writeable = False
            self._route_due = True
        self._prev_key, self._prev_pos = keys, pos.copy()  # (lane_pos is the caller's array)
        self._place_ms = self._now_ms
        return keys, pos

    def columns_at(self, keys: IntArray) -> dict[str, Any]:
        """The lane table's columns at ``keys`` looked up so far (by name, see
        :class:`~flowrun.kernel.state.OpenState`): kept while :meth:`read_place` hands out the
        same keys array (no car changed lanes), else empty."""
        if self._columns[0] is not keys:
            self._columns = (keys, {})
        return self._columns[1]

    def read_xy(self) -> tuple[FloatArray, FloatArray]:
        """Every car's map coordinates (this step), m."""
        xy = np.array(list(_flatten(map(self.fast.get_position, self.table.ids))), np.float64)
        return xy[0::2], xy[1::2]

    def read_odometer(self) -> FloatArray:
        """Distance every car has driven since it entered (this step), m."""
        ids = self.table.ids
        return np.fromiter(map(self.fast.get_distance, ids), np.float64, len(ids))

    def following(self, speed: FloatArray, lane_key: IntArray, lane_pos: FloatArray) -> Neighbours:
        """Leader, follower, headway, tailway and neighbour speeds of the current step."""
        following, lists = self._following, self._lists
        known = lists[2:] if lists and lists[0] is lane_key and lists[1] is lane_pos else None
        leader, follower, headway, tailway = following.compute(
            self.table, lane_key, lane_pos, self.route_of, known
        )
        if following.links is not None:  # few cars: neighbour speeds picked by the links
            return following.links.neighbours(speed, headway, tailway)
        return neighbours(speed, leader, follower, headway, tailway, following.complete)

    # ------------------------------------------------------------------ population
    def _follow_population(self, first: bool, removed: list[str]) -> IntArray | None:
        """Add the cars SUMO inserted, drop those that arrived (or were removed); each new
        row's row before (-1 for a car that just entered), ``None`` if the rows are kept."""
        fast, pop = self.fast, self.table
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
        arrived += removed
        if self._resync:  # teleports can take cars off the road: ask SUMO who is there
            self._resync = False
            now = self.api.vehicle.getIDList()
            present = set(now)
            arrived = [v for v in pop.ids if v not in present]
            entered = departed = [v for v in now if v not in pop]
        self.departed_ids, self.arrived_ids = departed, arrived
        self.flow_counts.append((len(departed), len(arrived)))
        if not entered and not arrived and self._version == pop.version:
            return None
        v = self.api.vehicle
        groups = [pop.class_index(v.getTypeID(vid)) for vid in entered]
        old_route_end = self.route_end
        src = pop.change(arrived, entered, groups)
        for vid in arrived:
            self.route_of.pop(vid, None)
        for vid, g in zip(entered, groups, strict=True):
            if g != pop.foreign:  # Flow's modes hold from a car's first step
                c = pop.classes[g]
                v.setSpeedMode(vid, c.speed_mode)
                v.setLaneChangeMode(vid, c.lane_change_mode)
        if src is None:  # nothing changed (e.g. a removed car was never seen)
            src = np.arange(pop.size)
        self._resize(src, old_route_end)
        self._version = pop.version
        return src

    def _resize(self, src: IntArray, old_route_end: IntArray) -> None:
        """Carry per-row state that outlives a step over to the new rows (``src``: each new
        row's row before the change, -1 for a car that just entered)."""
        pop, lanes = self.table, self.lanes
        n = pop.size
        kept = src >= 0
        carried = np.where(kept, src, 0)
        self.route_end = np.where(kept, old_route_end[carried] if old_route_end.size else -1, -1)
        if self._prev_key.size == old_route_end.size:  # the last places, row by row
            old_key, old_pos = self._prev_key, self._prev_pos
            self._prev_key = np.where(kept, old_key[carried], -1) if old_key.size else src.copy()
            self._prev_key.flags.writeable = False  # (a step may hand it out as its lane keys)
            self._prev_pos = np.where(kept, old_pos[carried], np.nan) if old_pos.size else \
                np.full(n, np.nan)  # fmt: skip
        else:
            self._place_ms = NEVER
        self._lists = None
        rows = (~kept | (self.route_end < 0)).nonzero()[0]
        get_route = self.api.vehicle.getRoute
        for r in rows.tolist():
            vid = pop.ids[r]
            route = tuple(get_route(vid))
            self.route_of[vid] = route
            self.route_end[r] = lanes.edge_pos.get(route[-1], -1) if route else -1

    def resync(self) -> None:
        """Check the population against SUMO's vehicle list at the next update (after a
        teleport, which the departed/arrived lists do not report)."""
        self._resync = True

    # ------------------------------------------------------------------ routes
    def _route_continuously(self, edge_index: IntArray) -> None:
        """ContinuousRouter on any network: a car on its route's last edge gets a new route
        starting on that edge (drawn from the edge's route choices)."""
        due = (self.table.continuous & (edge_index == self.route_end)).nonzero()[0]
        self._route_due = bool(due.size)  # (a rerouted car's route end changed: check again)
        if not due.size:
            return
        names = self.lanes.edge_names
        for r in due.tolist():
            edge = names[int(edge_index[r])]
            choices = self.spec.choices(edge)
            if not choices:
                self.route_end[r] = -1
                continue
            if len(choices) == 1:
                route = choices[0][0]
            else:
                probs = np.array([p for _, p in choices], dtype=np.float64)
                route = choices[int(self.rng.choice(len(choices), p=probs / probs.sum()))][0]
            self.reroute_now([r], [route])

    def reroute_now(self, rows: Sequence[int], routes: Sequence[Sequence[str]]) -> None:
        """Give the cars of ``rows`` new routes at once (a router during the update)."""
        for r, route in zip(rows, routes, strict=True):
            vid = self.table.ids[r]
            self.api.vehicle.setRoute(vid, list(route))
            self.route_chosen(r, route)

    def route_chosen(self, row: int, route: Sequence[str]) -> None:
        """Keep the route a car was given (by a router or ``choose_routes``)."""
        if not route:
            return
        self.route_of[self.table.ids[row]] = tuple(route)
        self.route_end[row] = self.lanes.edge_pos.get(route[-1], -1)
        self._route_due = True
