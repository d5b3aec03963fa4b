"""Commands to SUMO: accelerations, lane changes and routes, buffered and sent per step.

A mixin of :class:`~flowrun.kernel.vehicle.VehicleKernel`. Commands are kept in the kernel's
arrays until :meth:`VehicleCommands.send_commands`, which ``k.simulation.simulation_step``
calls right before SUMO's step (so Flow's ``apply_*; simulation_step(); update()`` works).
Lane changes, SUMO's and commanded ones alike, are found by comparing each step's lanes
with the step before (:class:`LaneChangeLog`).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Sequence
from itertools import compress, repeat
from typing import TYPE_CHECKING, Any

import numpy as np

from flowrun.kernel.following import SMALL
from flowrun.kernel.vehicle_api import ERROR
from flowrun.types import FloatArray, IntArray

if TYPE_CHECKING:
    from flowrun.kernel.open_reader import OpenReader
    from flowrun.kernel.population import Population
    from flowrun.kernel.ring_reader import RingReader
    from flowrun.kernel.state import VehicleState
    from flowrun.kernel.sumo import FastCalls
    from flowrun.networks.base import Edge, NetworkSpec

_sum = np.add.reduce
_consume = deque[object](maxlen=0).extend  # runs an iterator to its end, keeping nothing

#: ``slowDown`` duration, s: shorter than a step, so the new speed holds at the next step.
SLOW_DOWN_DURATION = 1e-3
#: ``changeLane`` duration, s: Flow's, so a commanded car keeps its new lane
LANE_CHANGE_HOLD = 100000.0
#: Flow's value for "no such vehicle" (``get_last_lc`` of an unknown or non-RL car)


def without_removed(
    cmd: np.ndarray, table: Population, removed: Iterable[str], back: Iterable[str]
) -> np.ndarray:
    """``cmd`` (one acceleration per row) with no command (NaN) for the cars removed this
    step and not put back: Flow commands only the cars it still lists, and a car re-added
    with ``k.vehicle.add`` is a new car SUMO has not inserted yet (``back``)."""
    again = set(back)
    rows = [table.row(v) for v in removed if v in table and v not in again]
    if not rows:
        return cmd
    cmd = cmd.copy()
    cmd[rows] = np.nan
    return cmd


class LaneChangeLog:
    """Who changed lane when: each step's (edge, lane) of every car against the step before.

    A car counts as changing lane when it is on the same edge as one step earlier, in
    another lane (moving onto the next edge, where lane numbers may differ, is no change).
    A lane change is stamped with the step after which it is first seen, counted from the
    start of the episode as ``k.simulation.step_count`` and Flow's ``time_counter``. The
    kernel keeps a log only once someone asks for it (lanes are then read every step).

    Attributes:
        step: the step of the last state looked at (-1 before the first).
        last: vehicle id -> step of its last lane change.
        changed: ids of the cars that changed lane in the last step.
        total: lane changes since the episode started.
    """

    def __init__(self) -> None:
        self.step = -1
        self.last: dict[str, int] = {}
        self.changed: list[str] = []
        self.total = 0
        self._seen: np.ndarray | None = None  # the lanes array of the last state looked at
        self._ids: list[str] = []
        self._edge = np.zeros(0, dtype=np.int64)
        self._version = -1

    def observe(
        self, lanes: np.ndarray, edge: np.ndarray, ids: list[str], version: int, step: int
    ) -> None:
        """Look at one step's state (a state already looked at is skipped).

        Args:
            lanes: every car's lane index (the kernel's array of this step, never written).
            edge: every car's edge as a number (same numbering every step).
            ids: the cars' ids, in the rows of ``lanes``.
            version: the population's version (rows unchanged while it is unchanged).
            step: the step of this state since the episode started.
        """
        if lanes is self._seen:
            return
        self.step = step
        prev_lanes, prev_edge, prev_ids = self._seen, self._edge, self._ids
        same_rows = version == self._version
        self._seen, self._edge, self._version = lanes, edge, version
        if not same_rows:  # the population's list changes in place when cars come and go
            self._ids = list(ids)
        self.changed = []
        if prev_lanes is None or not prev_ids or not ids:
            return
        if same_rows and prev_lanes.size == lanes.size:
            rows = np.flatnonzero((edge == prev_edge) & (lanes != prev_lanes)).tolist()
        else:
            where = {vid: r for r, vid in enumerate(prev_ids)}
            src = np.fromiter((where.get(v, -1) for v in ids), np.int64, len(ids))
            kept = src >= 0
            at = np.where(kept, src, 0)
            moved = kept & (edge == prev_edge[at]) & (lanes != prev_lanes[at])
            rows = np.flatnonzero(moved).tolist()
        self.changed = [ids[r] for r in rows]
        for vid in self.changed:
            self.last[vid] = self.step
        self.total += len(rows)


class VehicleCommands:
    """Flow's ``apply_acceleration``, ``apply_lane_change`` and ``choose_routes``: the
    commands of one step, buffered per row until :meth:`send_commands`.

    Args:
        size: the rows of the population now.
    """

    table: Population
    spec: NetworkSpec
    api: Any
    dt: float
    state: VehicleState
    reader: RingReader | OpenReader
    _fast: FastCalls | None

    def __init__(self, size: int) -> None:
        self._edge_by_id: dict[str, Edge] = {e.id: e for e in self.spec.edges}
        self._multi_lane = any(e.lanes > 1 for e in self.spec.edges)
        #: cars taken out with ``remove`` since the last update
        self._pending_removal: list[str] = []
        #: simulation steps this kernel has sent commands for (one per step since it attached)
        self._steps_sent = 0
        self._lc_log: LaneChangeLog | None = None
        self._max_speed_set: dict[str, float] = {}
        self.commands_for(size)

    def commands_for(self, size: int) -> None:
        """Empty command buffers for ``size`` rows (the population's rows changed)."""
        self._all = slice(0, size)
        self._no_cmd = np.full(size, np.nan)
        #: the accelerations commanded this step (NaN: none), m/s^2
        self.accel_cmd = self._no_cmd.copy()
        #: the accelerations sent at the last step (NaN: none), m/s^2
        self.last_cmd = np.full(size, np.nan)
        self._lane_change: dict[int, int] = {}
        self._routes: dict[int, list[str]] = {}

    def apply_acceleration(self, veh_ids: str | Sequence[str], acc: Any) -> None:
        """Command accelerations (m/s^2): next-step speed will be ``v + a*dt`` (Flow's rule)."""
        if isinstance(veh_ids, str):
            veh_ids = [veh_ids]
        flat = np.asarray(acc, dtype=np.float64).reshape(-1)
        if flat.size == len(veh_ids):  # (broadcast_to costs more than the common case)
            accs: Any = flat.tolist()
        else:
            accs = np.broadcast_to(flat, (len(veh_ids),))
        for vid, a in zip(veh_ids, accs, strict=True):
            self.accel_cmd[self.table.row(vid)] = a

    def apply_acceleration_rows(self, rows: IntArray, acc: FloatArray) -> None:
        """:meth:`apply_acceleration` by kernel row: ``acc[i]`` (m/s^2) to the car of
        ``rows[i]`` (distinct rows), whatever lane it is on."""
        self.accel_cmd[rows] = acc

    def apply_acceleration_idx(self, idx: np.ndarray | slice, acc: np.ndarray) -> None:
        """Command accelerations by vehicle index (the vectorised path controllers use).

        As in Flow, a car on a junction-internal lane is left to SUMO for that step.
        """
        self.accel_cmd[idx] = self.state.commandable(acc, idx)

    def apply_lane_change(self, veh_ids: str | Sequence[str], direction: Any) -> None:
        """Change lane: ``+1`` left, ``-1`` right, ``0`` stay (Flow's convention)."""
        if isinstance(veh_ids, str):
            veh_ids = [veh_ids]
        dirs = np.broadcast_to(np.asarray(direction).reshape(-1), (len(veh_ids),))
        if any(round(float(d)) not in (-1, 0, 1) for d in dirs):
            raise ValueError("Direction values for lane changes may only be: -1, 0, or 1.")
        for vid, d in zip(veh_ids, dirs, strict=True):
            if round(float(d)) != 0:
                self._lane_change[self.table.row(vid)] = int(np.sign(d))

    def choose_routes(self, veh_ids: str | Sequence[str], route_choices: Any) -> None:
        """Give vehicles new routes (lists of edge ids); ``None`` keeps the current one."""
        if isinstance(veh_ids, str):
            veh_ids, route_choices = [veh_ids], [route_choices]
        for vid, route in zip(veh_ids, route_choices, strict=True):
            if route is not None:
                self._routes[self.table.row(vid)] = list(route)

    # ------------------------------------------------------------------ lane changes
    def lane_change_log(self) -> LaneChangeLog:
        """The episode's :class:`LaneChangeLog`, brought up to the current step; lane
        changes are logged from the first call on (an env that counts them calls this at
        reset)."""
        log = self._lc_log
        if log is None:
            log = self._lc_log = LaneChangeLog()
        if self._multi_lane:
            lanes = self.state.lanes
            edge = self.state.edge_index
            if edge is None:  # a closed ring: lane numbers never change between edges
                edge = np.zeros(lanes.size, dtype=np.int64)
            # the state of step n (since the kernel attached) follows n sent commands
            log.observe(lanes, edge, self.table.ids, self.table.version, self._steps_sent)
        return log

    def get_last_lc(self, veh_id: str, error: float = ERROR) -> float:
        """Step of the RL car's last lane change (Flow's; ``-inf`` if it has not changed
        lane this episode, ``error`` for an unknown or non-RL car, as Flow). Steps count
        from the start of the episode, as ``env.time_counter``."""
        table = self.table
        if veh_id not in table or not table.is_rl[table.row(veh_id)]:
            return error
        return float(self.lane_change_log().last.get(veh_id, -math.inf))

    def get_lane_changes(self) -> list[str]:
        """Ids of the cars that changed lane in the last step (SUMO's or commanded)."""
        return list(self.lane_change_log().changed)

    @property
    def num_lane_changes(self) -> int:
        """Lane changes of all cars since the episode started."""
        return self.lane_change_log().total

    # ------------------------------------------------------------------ Flow's other commands
    def set_lane_change_mode(self, veh_id: str, mode: int) -> None:
        """Set the car's SUMO ``laneChangeMode`` (a Flow mode's int), at once."""
        self.api.vehicle.setLaneChangeMode(veh_id, int(mode))

    def get_lane_change_mode(self, veh_id: str) -> int:
        """The car's SUMO ``laneChangeMode``."""
        return int(self.api.vehicle.getLaneChangeMode(veh_id))

    def set_max_speed(self, veh_id: str, max_speed: float) -> None:
        """Set the car's maximum speed, m/s (SUMO's ``setMaxSpeed``, at once)."""
        self.api.vehicle.setMaxSpeed(veh_id, float(max_speed))
        self._max_speed_set[veh_id] = float(max_speed)

    def add(self, veh_id: str, type_id: str, edge: str, pos: float | str,
            lane: int | str, speed: float | str) -> bool:  # fmt: skip
        """Flow's ``k.vehicle.add``: insert a car of group ``type_id`` on ``edge`` at the
        next step, on the route of that edge; it joins the arrays when SUMO reports it
        departed (a car SUMO cannot place yet waits, as an inflow's cars do).

        Returns:
            ``False`` (and nothing is done) if a car of that id is already in the network
            or waiting to enter.

        Raises:
            ValueError: no route starts on ``edge``.
        """
        from flowrun.networks.routes import route_name

        if edge not in self.spec.routes and edge not in self.spec.route_choices:
            raise ValueError(f"no route starts on edge {edge!r}; known: {sorted(self.spec.routes)}")
        leaving = veh_id in self._pending_removal  # removed this step: may come back (Flow)
        if (veh_id in self.table and not leaving) or (
            veh_id in self.api.simulation.getPendingVehicles()
        ):
            return False
        self.api.vehicle.add(
            veh_id, route_name(edge), typeID=str(type_id), depart="now",
            departLane=str(lane), departPos=str(pos), departSpeed=str(speed),
        )  # fmt: skip
        return True

    def send_commands(self) -> None:
        """Send the buffered commands to SUMO and clear them (once per simulation step)."""
        if self._multi_lane and self._lc_log is not None:  # lanes before this step
            self.lane_change_log()
        self._steps_sent += 1
        v = self.api.vehicle
        ids = self.table.ids
        cmd = self.accel_cmd
        if self._pending_removal:  # cars removed this step get no command (Flow)
            back = self.api.simulation.getPendingVehicles()
            cmd = without_removed(cmd, self.table, self._pending_removal, back)
        assert self._fast is not None
        slow_down = self._fast.slow_down
        state = self.state
        # Flow's rule (v + a*dt), never below 0 nor above the lane's speed limit (with
        # speedMode 0 SUMO would let a commanded car exceed the limit).
        if len(ids) <= SMALL:
            self._send_few(cmd, slow_down)
        elif math.isfinite(_sum(cmd)):  # the common case: every car commanded, no indexing
            target = np.minimum(np.maximum(state.speed + cmd * self.dt, 0.0), state.speed_limit)
            _consume(map(slow_down, ids, target.tolist(), repeat(SLOW_DOWN_DURATION)))
        elif np.count_nonzero(finite := np.isfinite(cmd)):  # (.any() adds a Python layer)
            # the same formula on every row; only the finite commands are sent
            target = np.minimum(np.maximum(state.speed + cmd * self.dt, 0.0), state.speed_limit)
            sent = finite.tolist()
            _consume(map(slow_down, compress(ids, sent), compress(target.tolist(), sent),
                         repeat(SLOW_DOWN_DURATION)))  # fmt: skip
        for i, d in self._lane_change.items():
            if not math.isfinite(cmd[i]) and ids[i] in self._pending_removal:
                continue
            lanes = self._num_lanes(state.edges[i])
            target_lane = min(max(int(state.lanes[i]) + d, 0), lanes - 1)
            if target_lane != state.lanes[i]:
                v.changeLane(ids[i], target_lane, LANE_CHANGE_HOLD)
        for i, route in self._routes.items():
            v.setRoute(ids[i], route)
            self.reader.route_chosen(i, route)
        self.last_cmd = cmd
        self.accel_cmd = self._no_cmd.copy()
        self._lane_change = {}
        self._routes = {}

    def _send_few(self, cmd: np.ndarray, slow_down: Any) -> None:
        """The accelerations ``cmd`` (NaN: none) as ``slowDown`` to few cars: the numpy
        formula of :meth:`send_commands` on Python floats (the same operations in the same
        order, so the same speeds, bit for bit; numpy's cost is mostly per call)."""
        cmd_l = cmd.tolist()
        sent = None  # (a finite sum: every command is finite)
        if not math.isfinite(sum(cmd_l)):
            sent = [a - a == 0.0 for a in cmd_l]  # finite (NaN - NaN and inf - inf are NaN)
            if True not in sent:
                return
        state, dt = self.state, self.dt
        rows = zip(self.table.ids, cmd_l, state.speed.tolist(), state.speed_limit.tolist(),
                   strict=True)  # fmt: skip
        for vid, a, v, limit in rows if sent is None else compress(rows, sent):
            speed = v + a * dt
            speed = speed if speed > 0.0 else 0.0
            slow_down(vid, speed if speed < limit else limit, SLOW_DOWN_DURATION)

    def _num_lanes(self, edge_id: str) -> int:
        edge = self._edge_by_id.get(edge_id)
        if edge is not None:
            return edge.lanes
        table = self.reader.lanes
        facts = None if table is None else table.edge_facts.get(edge_id)
        return 1 if facts is None else facts[0]
