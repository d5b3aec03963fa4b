"""One step's vehicle state: arrays with one row per car in the network now.

A state is made by one of two readers at every vehicle update and replaced at the next:

- :class:`RingState` by :class:`~flowrun.kernel.ring_reader.RingReader` on a closed ring
  whose cars circle forever: every field is read or derived at once (two getters per car and
  one sort around the loop), except the edges and lane positions, derived when asked.
- :class:`OpenState` by :class:`~flowrun.kernel.open_reader.OpenReader` on any other
  network: speeds at once; lanes and positions, map coordinates and who follows whom are read
  from SUMO when first asked in the step (explicit cached properties), so a step nobody asks
  about costs one getter per car.

Both have the same fields (``speed``, ``leader``, ``headway``, ...), and the fields that
follow from who follows whom come from one function,
:func:`~flowrun.kernel.following.neighbours`. Flow's test hooks
(``set_headway``, ...) replace a field of the step's state by assignment.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Generic, Protocol, TypeVar, overload

import numpy as np

from flowrun.kernel.following import Neighbours
from flowrun.types import BoolArray, FloatArray, IntArray

if TYPE_CHECKING:
    from flowrun.kernel.geometry import RingEdges
    from flowrun.kernel.lanes import LaneTable


class OpenReads(Protocol):
    """What :class:`OpenState` asks of its reader (an
    :class:`~flowrun.kernel.open_reader.OpenReader`), lazily, once per step."""

    lanes: LaneTable
    read_xy_each_step: bool

    def read_place(self, speed: FloatArray) -> tuple[IntArray, FloatArray]: ...

    def columns_at(self, keys: IntArray) -> dict[str, Any]: ...

    def read_xy(self) -> tuple[FloatArray, FloatArray]: ...

    def read_odometer(self) -> FloatArray: ...

    def following(
        self, speed: FloatArray, lane_key: IntArray, lane_pos: FloatArray
    ) -> Neighbours: ...


T = TypeVar("T")


class cached_property(Generic[T]):  # named as functools'
    """A field computed when first read, then kept in the instance (``functools.cached_property``
    without the lock Python 3.11's takes at every first read: 2.5 -> 0.9 µs, and an open
    road's state has a dozen such reads per step). Assigning the field replaces the value."""

    def __init__(self, func: Callable[[Any], T]) -> None:
        self.func = func
        self.name = func.__name__
        self.__doc__ = func.__doc__

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    @overload
    def __get__(self, obj: None, owner: type | None = None) -> cached_property[T]: ...

    @overload
    def __get__(self, obj: object, owner: type | None = None) -> T: ...

    def __get__(self, obj: object | None, owner: type | None = None) -> T | cached_property[T]:
        if obj is None:
            return self
        value = obj.__dict__[self.name] = self.func(obj)
        return value


def _take_fields(fields: dict[str, Any], values: dict[str, Any]) -> None:
    """Add ``values`` (by field name) to an instance's ``fields``, where it has none yet
    (a value assigned before, e.g. by a test hook, stays)."""
    if fields.keys().isdisjoint(values):
        fields.update(values)
    else:
        for name, value in values.items():
            fields.setdefault(name, value)


@dataclass(eq=False)
class RingState:
    """The state on a closed ring, every field read at the update (see the module doc).

    Attributes:
        speed, prev_speed: m/s, now and one step before.
        dt: simulation step, s.
        position: front bumper along the ring, m. lanes: lane index.
        x, y: map coordinates, m (the last read ones when the env reads none).
        odometer: distance driven since the car entered, m.
        speed_limit: the speed limit where each car is, m/s.
        on_internal: all ``False`` (a ring has no junction).
        ring_edges: the ring's edges, for :attr:`edges` and :attr:`lane_pos`.
    """

    speed: FloatArray
    prev_speed: FloatArray
    dt: float
    position: FloatArray
    lanes: IntArray
    x: FloatArray
    y: FloatArray
    odometer: FloatArray
    speed_limit: FloatArray
    on_internal: BoolArray
    leader: IntArray
    follower: IntArray
    headway: FloatArray
    tailway: FloatArray
    leader_speed: FloatArray
    follower_speed: FloatArray
    follower_headway: FloatArray
    ring_edges: RingEdges

    #: every car's edge as a number: the ring's kernel keeps none (no lane table)
    edge_index: None = None

    @cached_property
    def accel_real(self) -> FloatArray:
        """Acceleration realised over the last step, m/s^2."""
        return (self.speed - self.prev_speed) / self.dt

    @cached_property
    def _located(self) -> tuple[IntArray, FloatArray]:
        return self.ring_edges.locate(self.position)

    @cached_property
    def lane_pos(self) -> FloatArray:
        """Position of every car on its lane, m (from the ring position)."""
        return self._located[1]

    @cached_property
    def edges(self) -> list[str]:
        """Edge id of every car (from the ring position)."""
        return self.ring_edges.edge_names(self._located[0])

    def commandable(self, acc: FloatArray, idx: Any) -> FloatArray:
        """``acc`` as commanded to the cars ``idx`` (on a ring, all of it)."""
        return acc

    def read_all(self) -> None:
        """Nothing: every field of a ring's state is read at the update."""


@dataclass(eq=False)
class OpenState:
    """The state on an open network: speeds read at the update, the rest when first asked.

    Attributes:
        speed, prev_speed: m/s, now and one step before (a car that just entered: now).
        dt: simulation step, s.
        reader: the reader that made this state and reads its other fields from SUMO.
    """

    speed: FloatArray
    prev_speed: FloatArray
    dt: float
    reader: OpenReads

    @cached_property
    def accel_real(self) -> FloatArray:
        """Acceleration realised over the last step, m/s^2."""
        return (self.speed - self.prev_speed) / self.dt

    # ------------------------------------------------------------------ where each car is
    @cached_property
    def place(self) -> tuple[IntArray, FloatArray]:
        """Every car's lane (a lane-table key) and position on it, m (read from SUMO).

        The lane table's columns at these keys that an earlier step already looked up (the
        reader hands out the same keys array while no car changed lanes) become this
        step's fields at once; a field this step already has keeps its value."""
        place = self.reader.read_place(self.speed)
        fields = self.__dict__
        fields.setdefault("lane_key", place[0])
        fields.setdefault("lane_pos", place[1])
        _take_fields(fields, self.reader.columns_at(place[0]))
        return place

    @cached_property
    def lane_key(self) -> IntArray:
        """Every car's lane as a :class:`~flowrun.kernel.lanes.LaneTable` key."""
        return self.place[0]

    @cached_property
    def lane_pos(self) -> FloatArray:
        """Position of every car on its lane, m."""
        return self.place[1]

    def _column(self, name: str, values: np.ndarray) -> Any:
        """``values`` (a lane-table column) at every car's lane key, kept by the reader for
        the next steps with the same keys (read-only: those steps hand out the same array)."""
        keys = self.lane_key
        column = values[keys]
        column.flags.writeable = False
        self.reader.columns_at(keys)[name] = column
        return column

    @cached_property
    def lanes(self) -> IntArray:
        """Lane index of every car."""
        return self._column("lanes", self.reader.lanes.lane_index)

    @cached_property
    def _lane_start(self) -> FloatArray:
        """The start of every car's edge along the network, m."""
        return self._column("_lane_start", self.reader.lanes.start)

    @cached_property
    def position(self) -> FloatArray:
        """Position along the network (its edge's start plus the lane position), m."""
        return self._lane_start + self.lane_pos

    @cached_property
    def speed_limit(self) -> FloatArray:
        """The speed limit of every car's lane, m/s."""
        return self._column("speed_limit", self.reader.lanes.speed_limit)

    @cached_property
    def on_internal(self) -> BoolArray:
        """Whether each car is on a junction-internal lane."""
        return self._column("on_internal", self.reader.lanes.internal)

    @cached_property
    def _any_internal(self) -> bool:
        """Whether any car is on a junction-internal lane."""
        anyone = bool(np.count_nonzero(self.on_internal))
        self.reader.columns_at(self.lane_key)["_any_internal"] = anyone
        return anyone

    @cached_property
    def edge_index(self) -> IntArray:
        """Every car's edge as an index into the lane table's ``edge_names``."""
        return self._column("edge_index", self.reader.lanes.edge_index)

    @cached_property
    def edges(self) -> list[str]:
        """Edge id of every car."""
        names = self.reader.lanes.edge_names
        return [names[e] for e in self.edge_index.tolist()]

    @cached_property
    def xy(self) -> tuple[FloatArray, FloatArray]:
        """Every car's map coordinates, m (read from SUMO)."""
        return self.reader.read_xy()

    @cached_property
    def x(self) -> FloatArray:
        """Map x coordinate of every car, m."""
        return self.xy[0]

    @cached_property
    def y(self) -> FloatArray:
        """Map y coordinate of every car, m."""
        return self.xy[1]

    @cached_property
    def odometer(self) -> FloatArray:
        """Distance every car has driven since it entered, m (read from SUMO)."""
        return self.reader.read_odometer()

    # ------------------------------------------------------------------ who follows whom
    @cached_property
    def neighbours(self) -> Neighbours:
        """Who follows whom, within lanes and across junctions (found when first asked);
        its fields become this step's at once (a field the step already has keeps its value)."""
        found = self.reader.following(self.speed, self.lane_key, self.lane_pos)
        _take_fields(self.__dict__, found.__dict__)
        return found

    @cached_property
    def leader(self) -> IntArray:
        """Row of the car ahead, -1 for none."""
        return self.neighbours.leader

    @cached_property
    def follower(self) -> IntArray:
        """Row of the car behind, -1 for none."""
        return self.neighbours.follower

    @cached_property
    def headway(self) -> FloatArray:
        """Gap to the leader's rear bumper, m (``inf``: none)."""
        return self.neighbours.headway

    @cached_property
    def tailway(self) -> FloatArray:
        """Gap of the follower's front bumper to this car's rear bumper, m."""
        return self.neighbours.tailway

    @cached_property
    def leader_speed(self) -> FloatArray:
        """The leader's speed (the car's own without one), m/s."""
        return self.neighbours.leader_speed

    @cached_property
    def follower_speed(self) -> FloatArray:
        """The follower's speed (the car's own without one), m/s."""
        return self.neighbours.follower_speed

    @cached_property
    def follower_headway(self) -> FloatArray:
        """The follower's headway to this car, m (``inf`` without one)."""
        return self.neighbours.follower_headway

    def read_all(self) -> None:
        """Read now every field this step has not read yet (before a car leaves mid-step)."""
        _ = self.neighbours
        if self.reader.read_xy_each_step:
            _ = self.xy

    def commandable(self, acc: FloatArray, idx: Any) -> FloatArray:
        """``acc`` as commanded to the cars ``idx``: as in Flow, a car on a junction-internal
        lane is left to SUMO for that step (no command, NaN)."""
        if not self._any_internal:  # (most steps: nobody on a junction)
            return acc
        return np.where(self.on_internal[idx], np.nan, acc)


VehicleState = RingState | OpenState
