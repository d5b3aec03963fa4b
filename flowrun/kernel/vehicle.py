"""Flow's ``k.vehicle``: the step's vehicle state, read once per step, and the commands sent
back to SUMO.

Every getter serves the :mod:`~flowrun.kernel.state` value made by :meth:`VehicleKernel.update`
(a :class:`~flowrun.kernel.state.RingState` on a closed ring, an
:class:`~flowrun.kernel.state.OpenState` elsewhere); none of them calls SUMO but to read a
field the step has not read yet. Commands (:meth:`apply_acceleration`, ...) are buffered and
sent in :meth:`send_commands` just before the simulation step.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from itertools import islice
from operator import attrgetter
from typing import Any

import numpy as np

from flowrun.kernel.geometry import RingPlacement
from flowrun.kernel.lanes import LaneTable
from flowrun.kernel.open_reader import OpenReader
from flowrun.kernel.population import Population, VehicleTable
from flowrun.kernel.ring_reader import RingReader, ring_fast_path
from flowrun.kernel.state import VehicleState
from flowrun.kernel.sumo import FastCalls
from flowrun.kernel.vehicle_api import FlowVehicleGetters
from flowrun.kernel.vehicle_commands import VehicleCommands
from flowrun.networks.base import NetworkSpec
from flowrun.types import BoolArray, CarFollowingInputs, FloatArray, IntArray

__all__ = ["VehicleKernel", "ring_fast_path"]

_Facts = tuple[FloatArray, FloatArray, FloatArray]


def _of_state(name: str) -> Any:
    """A read-only kernel attribute that is the field ``name`` of the step's state (a
    C-level getter: reading it runs no Python frame)."""
    return property(attrgetter(f"state.{name}"), doc=f"The step's ``state.{name}``.")


class VehicleKernel(VehicleCommands, FlowVehicleGetters):
    """Flow's ``k.vehicle``: per-step vehicle state and commands.

    ``table`` is the :class:`Population` (ids, groups, lengths, ... one row per vehicle in
    the network now); :attr:`state` the step's arrays over the same rows, made by the
    network's reader (:class:`RingReader` on a closed ring whose rows never change,
    :class:`OpenReader` elsewhere). The state's fields are also the kernel's own attributes
    (``speed``, ``leader``, ...), as Flow's code reads them.

    Args:
        initial: the vehicles placed at the start of the episode and every group's facts.
        spec: the network the vehicles drive on.
        dt: simulation step, s.
        rng: the generator route choices are drawn from (``ContinuousRouter``).
    """

    reader: RingReader | OpenReader
    state: VehicleState

    def __init__(
        self,
        initial: VehicleTable,
        spec: NetworkSpec,
        dt: float,
        rng: np.random.Generator | None = None,
    ) -> None:
        self.initial = initial
        self.table = Population(initial.classes)
        self.table.add(initial.ids, initial.group.tolist())
        self.spec = spec
        self.dt = dt
        self.rng = rng if rng is not None else np.random.default_rng(0)
        #: routers of whole groups, run at each update (set by the kernel's owner)
        self.group_routers: Any = None
        #: read every car's map coordinates at every update (else when asked)
        self.read_xy = True
        self.api: Any = None
        self._fast: FastCalls | None = None
        #: (first row, end row) of a group -> (population, its version, the group's facts)
        self._facts_of: dict[tuple[int, int], tuple[Population, int, _Facts]] = {}
        VehicleCommands.__init__(self, initial.size)
        FlowVehicleGetters.__init__(self)

    # ------------------------------------------------------------------ reading
    def attach(self, api: Any, lanes: LaneTable | None = None) -> None:
        """Bind to a freshly started simulation (``libsumo`` or ``traci`` module)."""
        self.api = api
        fast = self._fast = FastCalls.of(api)
        if ring_fast_path(self.spec, self.initial):
            self.reader = RingReader(self.table, self.initial, self.spec, self.dt, api, fast)
        else:
            lanes = lanes or LaneTable.read(api, self.spec)
            self.reader = OpenReader(self.table, self.spec, self.dt, self.rng, api, fast, lanes)
            self.reader.group_routers = self.group_routers
        self.reader.read_xy_each_step = self.read_xy

    def update(self, first: bool = False) -> None:
        """Read this step's state from SUMO (the reader reads what it reads at once; the
        rest, on an open network, when first asked), then run the routers."""
        reader = self.reader
        reader.read_xy_each_step = self.read_xy
        removed = self._pending_removal
        self._pending_removal = []
        self.state = reader.read(first, removed)
        if reader.rows_changed:
            self.commands_for(self.table.size)
        reader.route(self)

    def placement(self) -> RingPlacement:
        """Edges, lane positions and map coordinates of ring positions, for batches of steps,
        on the network of this episode (closed rings; reads the lane shapes once)."""
        reader = self.reader
        if not isinstance(reader, RingReader):
            raise TypeError("placement() is a closed ring's: this network's cars come and go")
        return reader.placement()

    def remove(self, veh_id: str) -> None:
        """Take a vehicle out of the simulation (it leaves the arrays at the next step)."""
        self.state.read_all()  # this step's state, read while the car is still there
        self.api.vehicle.remove(veh_id)
        self._pending_removal.append(veh_id)

    def reroute_now(self, rows: Sequence[int], routes: Sequence[Sequence[str]]) -> None:
        """Give the cars of ``rows`` new routes at once (a router during the update)."""
        reader = self.reader
        assert isinstance(reader, OpenReader), "routers run on open networks"
        reader.reroute_now(rows, routes)

    def resync(self) -> None:
        """Check the population against SUMO's vehicle list at the next update (after a
        teleport, which the departed/arrived lists do not report)."""
        self.reader.resync()

    # ------------------------------------------------------------------ controller inputs
    def inputs(self, idx: np.ndarray | slice, time: float) -> CarFollowingInputs:
        """The state a car-following controller needs, for the vehicles ``idx``."""
        s, t = self.state, self.table
        if isinstance(idx, slice) and idx == self._all:  # one group drives every car
            return CarFollowingInputs(
                s.speed, s.headway, s.leader_speed, s.follower_headway, s.follower_speed,
                s.speed_limit, self.dt, time, t.accels, t.decels, t.lengths,
            )  # fmt: skip
        max_accel, max_decel, length = self._group_facts(idx)
        return CarFollowingInputs(
            speed=s.speed[idx],
            headway=s.headway[idx],
            leader_speed=s.leader_speed[idx],
            follower_headway=s.follower_headway[idx],
            follower_speed=s.follower_speed[idx],
            speed_limit=s.speed_limit[idx],
            dt=self.dt,
            time=time,
            max_accel=max_accel,
            max_decel=max_decel,
            length=length,
        )

    def _group_facts(self, idx: np.ndarray | slice) -> _Facts:
        """The maximum accelerations, decelerations and lengths of the cars ``idx``; of a
        group's contiguous rows, sliced once per population (read-only views)."""
        t = self.table
        if not isinstance(idx, slice):
            return t.accels[idx], t.decels[idx], t.lengths[idx]
        cached = self._facts_of.get((idx.start, idx.stop))
        if cached is not None and cached[0] is t and cached[1] == t.version:
            return cached[2]
        facts = (t.accels[idx], t.decels[idx], t.lengths[idx])
        for view in facts:
            view.flags.writeable = False
        self._facts_of[idx.start, idx.stop] = (t, t.version, facts)
        return facts

    # ------------------------------------------------------------------ the network
    @property
    def lane_table(self) -> LaneTable | None:
        """The network's lanes as SUMO built them (``None`` on a closed ring, which needs none)."""
        return self.reader.lanes

    @property
    def edge_names(self) -> list[str]:
        """The network's edge ids, junction-internal ones included, as :attr:`edge_index`
        counts them (empty on a closed ring)."""
        lanes = self.lane_table
        return [] if lanes is None else lanes.edge_names

    @property
    def multi_lane(self) -> bool:
        """Whether any edge of the network has more than one lane."""
        return self._multi_lane

    @property
    def route_end(self) -> IntArray:
        """Every car's route's last edge, as an index into ``edge_names`` (-1 if unknown);
        kept by the kernel on open networks (as ``edge_index``), no SUMO call."""
        return self.reader.route_end

    @property
    def departed_ids(self) -> Sequence[str]:
        """Vehicles that entered the network in the last step."""
        return self.reader.departed_ids

    @property
    def arrived_ids(self) -> Sequence[str]:
        """Vehicles that left the network in the last step."""
        return self.reader.arrived_ids

    @property
    def _flow_counts(self) -> deque[tuple[int, int]]:
        return self.reader.flow_counts

    # ------------------------------------------------------------------ departures, arrivals
    def get_departed_ids(self) -> list[str]:
        """Vehicles that entered the network in the last step."""
        return list(self.departed_ids)

    def get_arrived_ids(self) -> list[str]:
        """Vehicles that left the network in the last step."""
        return list(self.arrived_ids)

    def get_num_arrived(self) -> int:
        """Number of vehicles that left the network in the last step."""
        return len(self.arrived_ids)

    def get_num_not_departed(self) -> int:
        """Vehicles SUMO has loaded (inflows) but not yet inserted, because there was no room
        (Flow's ``get_num_not_departed``; 0 before the simulation starts)."""
        if self.api is None:
            return 0
        return len(self.api.simulation.getPendingVehicles())

    def get_inflow_rate(self, time_span: float) -> float:
        """Vehicles that entered over the last ``time_span`` seconds, in veh/hour."""
        return self._rate(time_span, 0)

    def get_outflow_rate(self, time_span: float) -> float:
        """Vehicles that left over the last ``time_span`` seconds, in veh/hour."""
        return self._rate(time_span, 1)

    def _rate(self, time_span: float, column: int) -> float:
        steps = max(1, round(time_span / self.dt))
        # the last ``steps`` entries only (the deque keeps up to 100,000 steps)
        counts = [c[column] for c in islice(reversed(self._flow_counts), steps)]
        if not counts:
            return 0.0
        return sum(counts) * 3600.0 / (len(counts) * self.dt)

    # ------------------------------------------------------------------ the step's state
    # the fields of :class:`~flowrun.kernel.state.RingState` / ``OpenState`` (meaning, units)
    speed: FloatArray = _of_state("speed")
    prev_speed: FloatArray = _of_state("prev_speed")
    accel_real: FloatArray = _of_state("accel_real")
    position: FloatArray = _of_state("position")
    lanes: IntArray = _of_state("lanes")
    lane_pos: FloatArray = _of_state("lane_pos")
    edges: list[str] = _of_state("edges")
    edge_index: IntArray | None = _of_state("edge_index")
    x: FloatArray = _of_state("x")
    y: FloatArray = _of_state("y")
    odometer: FloatArray = _of_state("odometer")
    speed_limit: FloatArray = _of_state("speed_limit")
    on_internal: BoolArray = _of_state("on_internal")
    leader: IntArray = _of_state("leader")
    follower: IntArray = _of_state("follower")
    headway: FloatArray = _of_state("headway")
    tailway: FloatArray = _of_state("tailway")
    leader_speed: FloatArray = _of_state("leader_speed")
    follower_speed: FloatArray = _of_state("follower_speed")
    follower_headway: FloatArray = _of_state("follower_headway")
