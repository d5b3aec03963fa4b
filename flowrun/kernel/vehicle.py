"""Vehicle state, read once per step into arrays, and the commands sent back to SUMO.

Every getter serves the snapshot taken by :meth:`VehicleKernel.update`; none of them calls
SUMO. Commands (:meth:`apply_acceleration`, ...) are buffered and sent in :meth:`send_commands`
just before the simulation step.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Sequence
from itertools import chain, repeat
from typing import Any

import numpy as np

from flowrun.controllers.base import CarFollowingInputs
from flowrun.kernel.geometry import LaneGeometry, RingEdges, RingPlacement
from flowrun.kernel.snapshot import RingFollowing, VehicleTable, leaders_on_ring
from flowrun.kernel.sumo import FastCalls
from flowrun.networks.base import NetworkSpec

_sum = np.add.reduce
_flatten = chain.from_iterable
_consume = deque[object](maxlen=0).extend  # runs an iterator to its end, keeping nothing

#: ``slowDown`` duration, s: shorter than a step, so the new speed holds at the next step.
SLOW_DOWN_DURATION = 1e-3


class VehicleKernel:
    """Flow's ``k.vehicle``: per-step vehicle state and commands.

    Args:
        table: the fixed vehicle population of the episode (ids, groups, lengths, ...).
        spec: the network the vehicles drive on.
        dt: simulation step, s.
    """

    def __init__(self, table: VehicleTable, spec: NetworkSpec, dt: float) -> None:
        self.table = table
        self.spec = spec
        self.dt = dt
        self.api: Any = None
        self.read_xy = True
        n = table.size
        self._index = {vid: i for i, vid in enumerate(table.ids)}
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
        self.odometer = np.zeros(n)
        self.x = np.zeros(n)
        self.y = np.zeros(n)
        self.speed_limit = np.full(n, np.inf)
        self._lane_change: dict[int, int] = {}
        self._routes: dict[int, list[str]] = {}
        self._edge_by_id = {e.id: e for e in spec.edges}
        self._multi_lane = any(e.lanes > 1 for e in spec.edges)

    # ------------------------------------------------------------------ reading
    def attach(self, api: Any) -> None:
        """Bind to a freshly started simulation (``libsumo`` or ``traci`` module)."""
        self.api = api
        self._fast = FastCalls.of(api)
        spec = self.spec
        self._edge_ids = [e.id for e in spec.edges]
        self._edge_pos = {e: i for i, e in enumerate(self._edge_ids)}
        self._starts = np.array([spec.edge_starts[e] for e in self._edge_ids])
        self._ring_edges = RingEdges(self._starts, self._edge_ids)
        self._edge_speeds = np.array([e.speed for e in spec.edges])
        self._uniform_speed = bool(np.all(self._edge_speeds == self._edge_speeds[0]))
        start_idx = np.array(
            [self._edge_pos.get(e, 0) for e in self.table.start_edges], dtype=np.int64
        )
        self._start_position = self._starts[start_idx] + np.array(self.table.start_lane_pos)
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
        ids = self.table.ids
        self.prev_speed = self.speed
        n = len(ids)
        speed = np.fromiter(map(fast.get_speed, ids), np.float64, n)
        self._accel_real = None
        if self._multi_lane:
            self.lanes = np.array(list(map(self.api.vehicle.getLaneIndex, ids)), dtype=np.int64)
        if self.read_xy:
            # flattened first: numpy would otherwise inspect every (x, y) tuple's shape
            xy = np.array(list(_flatten(map(fast.get_position, ids))), dtype=np.float64)
            self.x, self.y = xy[0::2], xy[1::2]
        if self.spec.closed:
            self.odometer = np.fromiter(map(fast.get_distance, ids), np.float64, n)
            unwrapped = self._start_position + self.odometer
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
        else:
            self._update_open(self.api.vehicle, ids)
        if first:
            self.prev_speed = speed
        self.speed = speed
        if not self._multi_lane and self._following.complete:
            self.leader_speed = speed[self.leader]
            self.follower_speed = speed[self.follower]
            self.follower_headway = self.headway[self.follower]
        else:
            has_lead, has_fol = self.leader >= 0, self.follower >= 0
            self.leader_speed = np.where(has_lead, speed[self.leader], speed)
            self.follower_speed = np.where(has_fol, speed[self.follower], speed)
            self.follower_headway = np.where(has_fol, self.headway[self.follower], np.inf)

    @property
    def accel_real(self) -> np.ndarray:
        """Acceleration realised over the last step, m/s^2 (computed when first asked)."""
        if self._accel_real is None:
            self._accel_real = (self.speed - self.prev_speed) / self.dt
        return self._accel_real

    def _update_open(self, v: Any, ids: list[str]) -> None:
        """Generic path for open networks: edge and lane position straight from SUMO."""
        edges = list(map(v.getRoadID, ids))
        self._lane_pos = np.array(list(map(v.getLanePosition, ids)), dtype=np.float64)
        self.odometer = np.array(list(map(v.getDistance, ids)), dtype=np.float64)
        starts = self.spec.edge_starts
        self.position = np.array([starts.get(e, math.nan) for e in edges]) + self._lane_pos
        self._edges_cache = edges
        self._stale_edges = False
        by_id = self._edge_by_id
        self.speed_limit = np.array([by_id[e].speed if e in by_id else math.inf for e in edges])
        n = len(ids)
        self.leader = np.full(n, -1, dtype=np.int64)
        self.follower = np.full(n, -1, dtype=np.int64)
        self.headway = np.full(n, np.inf)

    def _derive_edges(self) -> None:
        if self._stale_edges:
            idx, self._lane_pos = self._ring_edges.locate(self.position)
            self._edges_cache = self._ring_edges.edge_names(idx)
            self._stale_edges = False

    @property
    def lane_pos(self) -> np.ndarray:
        """Position of every vehicle on its lane, m."""
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

    # ------------------------------------------------------------------ commands
    def apply_acceleration(self, veh_ids: str | Sequence[str], acc: Any) -> None:
        """Command accelerations (m/s^2): next-step speed will be ``v + a*dt`` (Flow's rule)."""
        if isinstance(veh_ids, str):
            veh_ids = [veh_ids]
        accs = np.broadcast_to(np.asarray(acc, dtype=np.float64).reshape(-1), (len(veh_ids),))
        for vid, a in zip(veh_ids, accs, strict=True):
            self.accel_cmd[self._index[vid]] = a

    def apply_acceleration_idx(self, idx: np.ndarray | slice, acc: np.ndarray) -> None:
        """Command accelerations by vehicle index (the vectorised path controllers use)."""
        self.accel_cmd[idx] = acc

    def apply_lane_change(self, veh_ids: str | Sequence[str], direction: Any) -> None:
        """Change lane: ``+1`` left, ``-1`` right, ``0`` stay (Flow's convention)."""
        if isinstance(veh_ids, str):
            veh_ids = [veh_ids]
        dirs = np.broadcast_to(np.asarray(direction).reshape(-1), (len(veh_ids),))
        for vid, d in zip(veh_ids, dirs, strict=True):
            if round(float(d)) != 0:
                self._lane_change[self._index[vid]] = int(np.sign(d))

    def choose_routes(self, veh_ids: str | Sequence[str], route_choices: Any) -> None:
        """Give vehicles new routes (lists of edge ids); ``None`` keeps the current one."""
        if isinstance(veh_ids, str):
            veh_ids, route_choices = [veh_ids], [route_choices]
        for vid, route in zip(veh_ids, route_choices, strict=True):
            if route is not None:
                self._routes[self._index[vid]] = list(route)

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
            edge = self._edge_by_id.get(self.edges[i])
            lanes = edge.lanes if edge is not None else 1
            target_lane = min(max(int(self.lanes[i]) + d, 0), lanes - 1)
            if target_lane != self.lanes[i]:
                v.changeLane(ids[i], target_lane, 100000.0)
        for i, route in self._routes.items():
            v.setRoute(ids[i], route)
            self._next_reroute[i] = np.inf  # a user-chosen route is not looped
        self.last_cmd = cmd
        self.accel_cmd = self._no_cmd.copy()
        self._lane_change = {}
        self._routes = {}

    # ------------------------------------------------------------------ controller inputs
    def inputs(self, idx: np.ndarray | slice, time: float) -> CarFollowingInputs:
        """The state a car-following controller needs, for the vehicles ``idx``."""
        if isinstance(idx, slice) and idx == self._all:  # one group drives every car
            return CarFollowingInputs(
                self.speed, self.headway, self.leader_speed, self.follower_headway,
                self.follower_speed, self.speed_limit, self.dt, time,
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
        )

    # ------------------------------------------------------------------ Flow's getters
    @property
    def num_vehicles(self) -> int:
        """Number of vehicles in the network."""
        return self.table.size

    @property
    def num_rl_vehicles(self) -> int:
        """Number of RL vehicles in the network."""
        return int(self.table.is_rl.sum())

    def get_ids(self) -> list[str]:
        """All vehicle ids, in placement order."""
        return list(self.table.ids)

    def get_rl_ids(self) -> list[str]:
        """Ids of the vehicles the RL agent drives."""
        return [vid for vid, rl in zip(self.table.ids, self.table.is_rl, strict=True) if rl]

    def get_human_ids(self) -> list[str]:
        """Ids of all vehicles the agent does not drive."""
        return [vid for vid, rl in zip(self.table.ids, self.table.is_rl, strict=True) if not rl]

    def get_controlled_ids(self) -> list[str]:
        """Ids of human vehicles whose acceleration a flowrun controller sets."""
        return [self.table.ids[i] for i in np.flatnonzero(self.table.commanded)]

    def get_ids_by_edge(self, edges: str | Iterable[str]) -> list[str]:
        """Ids of the vehicles on the given edge(s)."""
        wanted = {edges} if isinstance(edges, str) else set(edges)
        return [vid for vid, e in zip(self.table.ids, self.edges, strict=True) if e in wanted]

    def get_type(self, veh_id: str) -> str:
        """The vehicle's group name."""
        return self.table.types[self._index[veh_id]]

    def get_speed(self, veh_id: str | Sequence[str], error: float = -1001) -> Any:
        """Speed in m/s (a list for a list of ids)."""
        return self._get(self.speed, veh_id)

    def get_x_by_id(self, veh_id: str) -> float:
        """Position along the network (ring position), m."""
        return float(self.position[self._index[veh_id]])

    def get_position(self, veh_id: str | Sequence[str]) -> Any:
        """Position on the current lane, m."""
        return self._get(self.lane_pos, veh_id)

    def get_2d_position(self, veh_id: str) -> tuple[float, float]:
        """(x, y) coordinates, m."""
        i = self._index[veh_id]
        if not self.read_xy:
            x, y = self.api.vehicle.getPosition(veh_id)
            return float(x), float(y)
        return float(self.x[i]), float(self.y[i])

    def get_edge(self, veh_id: str | Sequence[str]) -> Any:
        """Edge id."""
        if isinstance(veh_id, str):
            return self.edges[self._index[veh_id]]
        return [self.edges[self._index[v]] for v in veh_id]

    def get_lane(self, veh_id: str | Sequence[str]) -> Any:
        """Lane index."""
        if isinstance(veh_id, str):
            return int(self.lanes[self._index[veh_id]])
        return [int(self.lanes[self._index[v]]) for v in veh_id]

    def get_headway(self, veh_id: str | Sequence[str]) -> Any:
        """Bumper-to-bumper gap to the leader, m (``inf`` without leader)."""
        return self._get(self.headway, veh_id)

    def get_leader(self, veh_id: str) -> str | None:
        """Id of the vehicle ahead in the same lane, or ``None``."""
        j = int(self.leader[self._index[veh_id]])
        return self.table.ids[j] if j >= 0 else None

    def leader_ids(self) -> list[str]:
        """Leader id of every vehicle (``""`` without leader); reused while the order holds."""
        if self._leader_ids[0] is not self.leader:
            ids = self.table.ids
            self._leader_ids = (
                self.leader,
                [ids[j] if j >= 0 else "" for j in self.leader.tolist()],
            )
        return self._leader_ids[1]

    def get_follower(self, veh_id: str) -> str | None:
        """Id of the vehicle behind in the same lane, or ``None``."""
        j = int(self.follower[self._index[veh_id]])
        return self.table.ids[j] if j >= 0 else None

    def get_length(self, veh_id: str) -> float:
        """Vehicle length, m."""
        return float(self.table.lengths[self._index[veh_id]])

    def get_distance(self, veh_id: str) -> float:
        """Distance travelled since the episode started, m."""
        return float(self.odometer[self._index[veh_id]])

    def get_realized_accel(self, veh_id: str) -> float:
        """Acceleration realised over the last step, m/s^2."""
        return float(self.accel_real[self._index[veh_id]])

    def get_accel(self, veh_id: str) -> float | None:
        """Acceleration commanded for the last step, m/s^2 (``None`` when SUMO drove)."""
        a = float(self.last_cmd[self._index[veh_id]])
        return a if math.isfinite(a) else None

    def get_max_speed(self, veh_id: str) -> float:
        """The vehicle type's maximum speed, m/s."""
        return float(self.table.max_speeds[self._index[veh_id]])

    def get_route(self, veh_id: str) -> tuple[str, ...]:
        """The route assigned to the vehicle's current edge."""
        return self.spec.routes.get(self.get_edge(veh_id), ())

    def _get(self, array: np.ndarray, veh_id: str | Sequence[str]) -> Any:
        if isinstance(veh_id, str):
            return float(array[self._index[veh_id]])
        return [float(array[self._index[v]]) for v in veh_id]
