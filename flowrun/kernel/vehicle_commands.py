"""Commands to SUMO: accelerations, lane changes and routes, buffered and sent per step.

A mixin of :class:`~flowrun.kernel.vehicle.VehicleKernel`. Commands are kept in the kernel's
arrays until :meth:`VehicleCommands.send_commands`, which ``k.simulation.simulation_step``
calls right before SUMO's step (so Flow's ``apply_*; simulation_step(); update()`` works).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from itertools import repeat
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from flowrun.kernel.lanes import LaneTable
    from flowrun.kernel.population import Population
    from flowrun.kernel.sumo import FastCalls
    from flowrun.networks.base import Edge

_sum = np.add.reduce
_consume = deque[object](maxlen=0).extend  # runs an iterator to its end, keeping nothing

#: ``slowDown`` duration, s: shorter than a step, so the new speed holds at the next step.
SLOW_DOWN_DURATION = 1e-3


class VehicleCommands:
    """Flow's ``apply_acceleration``, ``apply_lane_change`` and ``choose_routes``."""

    table: Population
    api: Any
    dt: float
    ring_path: bool
    speed: np.ndarray
    speed_limit: np.ndarray
    lanes: np.ndarray
    on_internal: np.ndarray
    accel_cmd: np.ndarray
    last_cmd: np.ndarray
    _no_cmd: np.ndarray
    _fast: FastCalls
    _lane_change: dict[int, int]
    _routes: dict[int, list[str]]
    _next_reroute: np.ndarray
    _route_end: np.ndarray
    _route_of: dict[str, tuple[str, ...]]
    _lanes: LaneTable | None
    _edge_by_id: dict[str, Edge]

    @property
    def edges(self) -> list[str]:  # implemented by the kernel
        raise NotImplementedError

    def apply_acceleration(self, veh_ids: str | Sequence[str], acc: Any) -> None:
        """Command accelerations (m/s^2): next-step speed will be ``v + a*dt`` (Flow's rule)."""
        if isinstance(veh_ids, str):
            veh_ids = [veh_ids]
        accs = np.broadcast_to(np.asarray(acc, dtype=np.float64).reshape(-1), (len(veh_ids),))
        for vid, a in zip(veh_ids, accs, strict=True):
            self.accel_cmd[self.table.row(vid)] = a

    def apply_acceleration_idx(self, idx: np.ndarray | slice, acc: np.ndarray) -> None:
        """Command accelerations by vehicle index (the vectorised path controllers use).

        As in Flow, a car on a junction-internal lane is left to SUMO for that step.
        """
        if not self.ring_path:
            acc = np.where(self.on_internal[idx], np.nan, acc)
        self.accel_cmd[idx] = acc

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

    def send_commands(self) -> None:
        """Send the buffered commands to SUMO and clear them."""
        v = self.api.vehicle
        ids = self.table.ids
        cmd = self.accel_cmd
        slow_down = self._fast.slow_down
        # Flow's rule (v + a*dt), never below 0 nor above the lane's speed limit (with
        # speedMode 0 SUMO would let a commanded car exceed the limit).
        if math.isfinite(_sum(cmd)):  # the common case: every car commanded, no indexing
            target = np.minimum(np.maximum(self.speed + cmd * self.dt, 0.0), self.speed_limit)
            _consume(map(slow_down, ids, target.tolist(), repeat(SLOW_DOWN_DURATION)))
        elif (finite := np.isfinite(cmd)).any():
            todo = np.flatnonzero(finite)
            target = np.minimum(
                np.maximum(self.speed[todo] + cmd[todo] * self.dt, 0.0), self.speed_limit[todo]
            )
            for i, speed in zip(todo.tolist(), target.tolist(), strict=True):
                slow_down(ids[i], speed, SLOW_DOWN_DURATION)
        for i, d in self._lane_change.items():
            lanes = self._num_lanes(self.edges[i])
            target_lane = min(max(int(self.lanes[i]) + d, 0), lanes - 1)
            if target_lane != self.lanes[i]:
                v.changeLane(ids[i], target_lane, 100000.0)
        for i, route in self._routes.items():
            v.setRoute(ids[i], route)
            if self.ring_path:
                self._next_reroute[i] = np.inf  # a user-chosen route is not looped
            elif route and self._lanes is not None:
                self._route_end[i] = self._lanes.edge_pos.get(route[-1], -1)
                self._route_of[ids[i]] = tuple(route)
        self.last_cmd = cmd
        self.accel_cmd = self._no_cmd.copy()
        self._lane_change = {}
        self._routes = {}

    def _num_lanes(self, edge_id: str) -> int:
        edge = self._edge_by_id.get(edge_id)
        if edge is not None:
            return edge.lanes
        facts = None if self._lanes is None else self._lanes.edge_facts.get(edge_id)
        return 1 if facts is None else facts[0]

