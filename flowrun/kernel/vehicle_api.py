"""Flow's ``k.vehicle`` getters, served from the per-step snapshot (a few ask SUMO on demand).

A mixin of :class:`~flowrun.kernel.vehicle.VehicleKernel`: it reads the kernel's compact
per-step arrays and its :class:`~flowrun.kernel.population.Population`. Unknown vehicle ids
give Flow's error values (``-1001`` for numbers, ``""`` for edges) where Flow has them.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from itertools import repeat
from typing import TYPE_CHECKING, Any

import numpy as np

from flowrun.flow_values import FLOW_ERROR
from flowrun.kernel.lane_neighbours import (
    NO_NEIGHBOUR_GAP,
    LaneGraphView,
    LaneNeighbours,
    lane_neighbours,
)

if TYPE_CHECKING:
    from flowrun.kernel.population import Population, VehicleTable
    from flowrun.kernel.state import VehicleState
    from flowrun.networks.base import NetworkSpec

#: Flow's value for "no such vehicle" in numeric getters.
ERROR = FLOW_ERROR

#: Density of gasoline, g per litre, used to turn SUMO's fuel mass into volume.
GASOLINE_G_PER_L = 745.0
#: Milligrams of gasoline in one US gallon (3.785411784 l).
MG_PER_GALLON = GASOLINE_G_PER_L * 1000.0 * 3.785411784

#: Flow's vehicle colours (red, green, blue).
RED, CYAN, WHITE = (255, 0, 0), (0, 255, 255), (255, 255, 255)


class FlowVehicleGetters:
    """Flow's getters over the kernel's arrays (see :class:`VehicleKernel`)."""

    table: Population
    initial: VehicleTable
    spec: NetworkSpec
    dt: float
    api: Any
    read_xy: bool
    state: VehicleState
    last_cmd: np.ndarray
    _pending_removal: list[str]
    #: set by the environment: Flow's per-vehicle controller objects
    controllers: Any = None
    #: the network as Flow's lane-neighbour search walks it (set by the kernel at reset)
    lane_view: LaneGraphView
    _max_speed_set: dict[str, float]

    def __init__(self) -> None:
        #: vehicles an environment marked as observed, in order
        self._observed: dict[str, None] = {}
        #: (the leader rows, the ids they were read with, their leaders' ids)
        self._leader_ids: tuple[np.ndarray | None, list[str] | None, list[str]] = (None, None, [])
        self._initial_row_cache: dict[str, int] | None = None

    # ------------------------------------------------------------------ Flow's getters
    @property
    def num_vehicles(self) -> int:
        """Number of vehicles in the network (a car removed this step no longer counts)."""
        removed = self._pending_removal
        return self.table.size - (len(set(removed)) if removed else 0)

    @property
    def num_rl_vehicles(self) -> int:
        """Number of RL vehicles in the network."""
        return len(self.get_rl_ids()) if self._pending_removal else int(self.table.is_rl.sum())

    def _removed(self) -> set[str]:
        """Ids taken out with :meth:`remove` this step: gone for Flow's getters at once, as in
        Flow, although their rows leave the arrays only at the next simulation step."""
        return set(self._pending_removal) if self._pending_removal else set()

    def _present(self, ids: list[str]) -> list[str]:
        if not self._pending_removal:  # the usual step: no set built
            return ids
        gone = self._removed()
        return [vid for vid in ids if vid not in gone]

    def get_ids(self) -> list[str]:
        """All vehicle ids, in placement order."""
        return self._present(list(self.table.ids))

    def get_rl_ids(self) -> list[str]:
        """Ids of the vehicles the RL agent drives."""
        ids = self.table.ids
        return self._present([vid for vid, rl in zip(ids, self.table.is_rl, strict=True) if rl])

    def get_human_ids(self) -> list[str]:
        """Ids of all vehicles the agent does not drive."""
        ids = self.table.ids
        return self._present(
            [vid for vid, rl in zip(ids, self.table.is_rl, strict=True) if not rl]
        )

    def get_controlled_ids(self) -> list[str]:
        """Ids of human vehicles whose acceleration a flowrun controller sets."""
        return self._present([self.table.ids[i] for i in np.flatnonzero(self.table.commanded)])

    def get_controlled_lc_ids(self) -> list[str]:
        """Ids of vehicles whose lane changes a flowrun lane-change controller decides."""
        rows = np.flatnonzero(self.table.lane_controlled)
        return self._present([self.table.ids[i] for i in rows])

    # ------------------------------------------------------------------ controllers
    def get_acc_controller(self, veh_id: str) -> Any:
        """The vehicle's acceleration controller (Flow's ``get_action(env)`` interface)."""
        return self._require_controllers().acceleration(veh_id, self._group_of(veh_id))

    def get_lane_changing_controller(self, veh_id: str) -> Any:
        """The lane-change controller of the vehicle's group (its own for a Flow-style class)."""
        return self._require_controllers().lane_changing(self._group_of(veh_id), veh_id)

    def get_routing_controller(self, veh_id: str) -> Any:
        """The routing controller of the vehicle's group (``None`` without one; its own for a
        Flow-style class)."""
        return self._require_controllers().routing(self._group_of(veh_id), veh_id)

    def _group_of(self, veh_id: str) -> int:
        return int(self.table.group[self.table.row(veh_id)])

    def _require_controllers(self) -> Any:
        if self.controllers is None:
            raise RuntimeError("controllers are known once an environment has reset")
        return self.controllers

    # ------------------------------------------------------------------ Flow's extras
    def get_observed_ids(self) -> list[str]:
        """Vehicles an environment marked as observed (Flow: coloured in the GUI)."""
        return [v for v in self._observed if v in self.table]

    def set_observed(self, veh_id: str) -> None:
        """Mark a vehicle as observed."""
        self._observed.setdefault(veh_id, None)

    def set_observed_many(self, veh_ids: Iterable[str]) -> None:
        """Mark several vehicles as observed (ids not in the network are skipped)."""
        self._observed.update(zip(filter(self.table.present, veh_ids), repeat(None)))

    def remove_observed(self, veh_id: str) -> None:
        """Unmark a vehicle as observed."""
        self._observed.pop(veh_id, None)

    def update_vehicle_colors(self) -> None:
        """Flow's colours, for a rendered run: RL cars red, observed cars cyan, the other
        cars white; then the observed marks are cleared (an env marks them every step)."""
        observed = set(self._observed)
        for vid, rl in zip(self.table.ids, self.table.is_rl.tolist(), strict=True):
            color = RED if rl else CYAN if vid in observed else WHITE
            self.set_color(vid, color)
        self._observed.clear()

    def get_color(self, veh_id: str) -> tuple[int, int, int]:
        """The vehicle's colour (red, green, blue; 0-255)."""
        r, g, b, _ = self.api.vehicle.getColor(veh_id)
        return int(r), int(g), int(b)

    def set_color(self, veh_id: str, color: tuple[int, int, int]) -> None:
        """Set the vehicle's colour (red, green, blue; 0-255)."""
        r, g, b = color
        self.api.vehicle.setColor(veh_id, (int(r), int(g), int(b), 255))

    def set_headway(self, veh_id: str, headway: float) -> None:
        """Overwrite the vehicle's headway until the next step (Flow's test hook)."""
        self.state.headway = self.state.headway.copy()  # frames may hold the old array
        self.state.headway[self.table.row(veh_id)] = headway

    def set_leader(self, veh_id: str, leader: str | None) -> None:
        """Overwrite the vehicle's leader until the next step (Flow's test hook)."""
        self.state.leader = self.state.leader.copy()
        self.state.leader[self.table.row(veh_id)] = self.table.row(leader) if leader else -1

    def set_follower(self, veh_id: str, follower: str | None) -> None:
        """Overwrite the vehicle's follower until the next step (Flow's test hook)."""
        self.state.follower = self.state.follower.copy()
        self.state.follower[self.table.row(veh_id)] = self.table.row(follower) if follower else -1

    def test_set_speed(self, veh_id: str, speed: float) -> None:
        """Overwrite the vehicle's speed until the next step (Flow's test hook)."""
        self.state.speed = self.state.speed.copy()
        self.state.speed[self.table.row(veh_id)] = speed

    def test_set_edge(self, veh_id: str, edge: str) -> None:
        """Overwrite the vehicle's edge until the next step (Flow's test hook)."""
        edges = list(self.state.edges)
        edges[self.table.row(veh_id)] = edge
        self.state.edges = edges

    def get_ids_by_edge(self, edges: str | Iterable[str]) -> list[str]:
        """Ids of the vehicles on the given edge(s)."""
        wanted = {edges} if isinstance(edges, str) else set(edges)
        return [vid for vid, e in zip(self.table.ids, self.state.edges, strict=True) if e in wanted]

    def get_type(self, veh_id: str) -> str:
        """The vehicle's group name."""
        return self.table.types[self.table.row(veh_id)]

    def get_speed(self, veh_id: str | Sequence[str], error: float = ERROR) -> Any:
        """Speed in m/s (a list for a list of ids; ``error`` for an unknown id)."""
        return self._get(self.state.speed, veh_id, error)

    def get_fuel_consumption(self, veh_id: str | Sequence[str], error: float = ERROR) -> Any:
        """Fuel consumption in US gallons/s over the last step, asked of SUMO now (no per-step
        cost); a list for a list of ids, ``error`` for an unknown id.

        SUMO 1.28 gives mg/s (Flow's kernel multiplied it as ml/s); this divides by
        :data:`GASOLINE_G_PER_L` (745 g of gasoline per litre) and 3.785411784 l per gallon,
        so Flow's ``miles_per_gallon`` gets the gallons it expects.
        """
        if not isinstance(veh_id, str):
            return [self.get_fuel_consumption(v, error) for v in veh_id]
        if veh_id not in self.table or veh_id in self._removed():
            return error
        mg_per_s = float(self.api.vehicle.getFuelConsumption(veh_id))
        return mg_per_s / MG_PER_GALLON

    def get_previous_speed(self, veh_id: str | Sequence[str], error: float = ERROR) -> Any:
        """Speed at the step before, m/s."""
        return self._get(self.state.prev_speed, veh_id, error)

    def get_x_by_id(self, veh_id: str) -> float:
        """Position along the network, m: the start of the car's edge (junction-internal
        edges included, see ``k.network.get_x``) plus its lane position; 0 if unknown."""
        if veh_id not in self.table:
            return 0.0
        return float(self.state.position[self.table.row(veh_id)])

    def get_position(self, veh_id: str | Sequence[str], error: float = ERROR) -> Any:
        """Position on the current lane, m."""
        return self._get(self.state.lane_pos, veh_id, error)

    def get_2d_position(self, veh_id: str) -> tuple[float, float]:
        """(x, y) coordinates, m."""
        i = self.table.row(veh_id)
        if not self.read_xy:
            x, y = self.api.vehicle.getPosition(veh_id)
            return float(x), float(y)
        return float(self.state.x[i]), float(self.state.y[i])

    def get_edge(self, veh_id: str | Sequence[str], error: str = "") -> Any:
        """Edge id (``error`` for an unknown id)."""
        if not isinstance(veh_id, str):
            return [self.get_edge(v, error) for v in veh_id]
        if veh_id not in self.table:
            return error
        return self.state.edges[self.table.row(veh_id)]

    def get_lane(self, veh_id: str | Sequence[str], error: int = int(ERROR)) -> Any:
        """Lane index."""
        if not isinstance(veh_id, str):
            return [self.get_lane(v, error) for v in veh_id]
        if veh_id not in self.table:
            return error
        return int(self.state.lanes[self.table.row(veh_id)])

    def get_headway(self, veh_id: str | Sequence[str], error: float = ERROR) -> Any:
        """Bumper-to-bumper gap to the leader, m: Flow's 1000 without a leader.

        The kernel's own :attr:`headway` array keeps ``inf`` there: the vectorised
        controllers read that as "no leader", as Flow's test the leader id.
        """
        h = self._get(self.state.headway, veh_id, error)
        if isinstance(h, list):
            return [NO_NEIGHBOUR_GAP if x == math.inf else x for x in h]
        return NO_NEIGHBOUR_GAP if h == math.inf else h

    def get_tailway(self, veh_id: str | Sequence[str], error: float = ERROR) -> Any:
        """Gap from the follower's front bumper to this car's rear bumper, m."""
        return self._get(self.state.tailway, veh_id, error)

    def get_leader(self, veh_id: str) -> str | None:
        """Id of the vehicle ahead (in the lane, or past its end along the route) or ``None``."""
        if veh_id not in self.table:
            return None
        j = int(self.state.leader[self.table.row(veh_id)])
        return self.table.ids[j] if j >= 0 else None

    def leader_ids(self) -> list[str]:
        """Leader id of every vehicle (``""`` without leader); reused while the order holds
        (the same rows, of the same cars: a reader keeps its leader rows while they stay,
        and the population's ids are a new list whenever cars come or go)."""
        leader, ids = self.state.leader, self.table.ids
        if self._leader_ids[0] is not leader or self._leader_ids[1] is not ids:
            self._leader_ids = (leader, ids, [ids[j] if j >= 0 else "" for j in leader.tolist()])
        return self._leader_ids[2]

    def get_follower(self, veh_id: str) -> str | None:
        """Id of the vehicle behind (in the lane, or before its start), or ``None``."""
        if veh_id not in self.table:
            return None
        j = int(self.state.follower[self.table.row(veh_id)])
        return self.table.ids[j] if j >= 0 else None

    def get_length(self, veh_id: str) -> float:
        """Vehicle length, m."""
        return float(self.table.lengths[self.table.row(veh_id)])

    def get_distance(self, veh_id: str) -> float:
        """Distance travelled since the episode started, m."""
        return float(self.state.odometer[self.table.row(veh_id)])

    def get_realized_accel(self, veh_id: str) -> float:
        """Acceleration realised over the last step, m/s^2."""
        return float(self.state.accel_real[self.table.row(veh_id)])

    def get_accel(self, veh_id: str) -> float | None:
        """Acceleration commanded for the last step, m/s^2 (``None`` when SUMO drove)."""
        a = float(self.last_cmd[self.table.row(veh_id)])
        return a if math.isfinite(a) else None

    def get_initial_speed(self, veh_id: str | Sequence[str], error: float | None = ERROR) -> Any:
        """Speed the vehicle entered the network with, m/s (Flow's ``get_initial_speed``:
        ``VehicleParams.add(initial_speed=...)``; ``error`` for an id not placed at the start)."""
        if not isinstance(veh_id, str):
            return [self.get_initial_speed(v, error) for v in veh_id]
        rows = self._initial_rows()
        if veh_id not in rows:
            return error
        return float(self.initial.initial_speeds[rows[veh_id]])

    def _initial_rows(self) -> dict[str, int]:
        rows = self._initial_row_cache
        if rows is None:
            rows = {vid: i for i, vid in enumerate(self.initial.ids)}
            self._initial_row_cache = rows
        return rows

    def get_max_speed(self, veh_id: str) -> float:
        """The vehicle's maximum speed, m/s: its type's, or the last ``set_max_speed``."""
        chosen = self._max_speed_set.get(veh_id)
        if chosen is not None:
            return float(chosen)
        return float(self.table.max_speeds[self.table.row(veh_id)])

    def get_route(self, veh_id: str) -> tuple[str, ...]:
        """The edges of the vehicle's route (SUMO's; empty for an unknown id)."""
        if veh_id not in self.table:
            return ()
        return tuple(self.api.vehicle.getRoute(veh_id))

    # ------------------------------------------------------------------ lanes around a car
    def get_lane_leaders(self, veh_id: str) -> list[str]:
        """The nearest car ahead on each lane of the car's edge, or on the lanes those lead
        to (``""`` where none); Flow's rule, see :mod:`flowrun.kernel.lane_neighbours`."""
        return [self._ids_or_blank(j) for j in self._lane_neighbours(veh_id).leaders]

    def get_lane_headways(self, veh_id: str) -> list[float]:
        """Gap to the lane leader on each lane, m (Flow's 1000 where none)."""
        return self._lane_neighbours(veh_id).headways

    def get_lane_followers(self, veh_id: str) -> list[str]:
        """The nearest car behind on each lane of the car's edge, or on the lanes leading
        into them (``""`` where none)."""
        return [self._ids_or_blank(j) for j in self._lane_neighbours(veh_id).followers]

    def get_lane_tailways(self, veh_id: str) -> list[float]:
        """Gap to the lane follower on each lane, m (Flow's 1000 where none)."""
        return self._lane_neighbours(veh_id).tailways

    def get_lane_leaders_speed(self, veh_id: str) -> list[float]:
        """Speed of the lane leader on each lane (0 where none), m/s."""
        rows = self._lane_neighbours(veh_id).leaders
        return [float(self.state.speed[j]) if j >= 0 else 0.0 for j in rows]

    def get_lane_followers_speed(self, veh_id: str) -> list[float]:
        """Speed of the lane follower on each lane (0 where none), m/s."""
        rows = self._lane_neighbours(veh_id).followers
        return [float(self.state.speed[j]) if j >= 0 else 0.0 for j in rows]

    def _lane_neighbours(self, veh_id: str) -> LaneNeighbours:
        s = self.state
        return lane_neighbours(
            self.table.row(veh_id), s.edges, s.lanes, s.lane_pos, self.table.lengths, self.lane_view
        )

    def _ids_or_blank(self, row: int) -> str:
        return self.table.ids[row] if row >= 0 else ""

    def _get(self, array: np.ndarray, veh_id: str | Sequence[str], error: Any = ERROR) -> Any:
        table = self.table
        if self._pending_removal:  # removed this step: unknown, as in Flow
            gone = self._removed()
            if isinstance(veh_id, str):
                known = veh_id in table and veh_id not in gone
                return float(array[table.row(veh_id)]) if known else error
            return [
                float(array[table.row(v)]) if v in table and v not in gone else error
                for v in veh_id
            ]
        if isinstance(veh_id, str):
            return float(array[table.row(veh_id)]) if veh_id in table else error
        return [float(array[table.row(v)]) if v in table else error for v in veh_id]
