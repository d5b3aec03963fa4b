"""The vehicles in the network now: a stable slot per vehicle, compact arrays of the live ones.

Vehicles come and go (inflows, arrivals, removals). Each vehicle keeps one *slot* for as long
as it is in the network (free slots are reused); the kernel's per-step arrays are *compact*:
row ``r`` is the ``r``-th live vehicle, in the order they entered. On a step where the
population changes, the compact static arrays are gathered again with one numpy index per
attribute; on other steps nothing is rebuilt. A closed ring's population never changes.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from itertools import compress

import numpy as np

from flowrun.types import IntArray


@dataclass(frozen=True)
class VehicleClass:
    """Static facts shared by all vehicles of one group (one ``VehicleParams.add`` call).

    Attributes:
        name: group name, also the SUMO vType id.
        is_rl: driven by the RL agent.
        commanded: a flowrun (non-SUMO, non-RL) controller sets its acceleration.
        continuous: routed by ``ContinuousRouter``.
        lane_controlled: a flowrun lane-change controller (not SUMO's) decides its lanes.
        length: vehicle length, m.
        min_gap: SUMO ``minGap``, m.
        max_speed: vehicle-type maximum speed, m/s.
        accel: SUMO ``accel`` (maximum acceleration), m/s^2.
        decel: SUMO ``decel`` (maximum comfortable deceleration, positive), m/s^2.
        speed_mode: SUMO speedMode bit set.
        lane_change_mode: SUMO laneChangeMode bit set.
    """

    name: str
    is_rl: bool = False
    commanded: bool = False
    continuous: bool = False
    lane_controlled: bool = False
    length: float = 5.0
    min_gap: float = 2.5
    max_speed: float = 30.0
    accel: float = 2.6
    decel: float = 7.5
    speed_mode: int = 0
    lane_change_mode: int = 512


#: vehicles of a SUMO vType that no vehicle group declares
FOREIGN = VehicleClass("<sumo>", speed_mode=31, lane_change_mode=1621)


@dataclass(frozen=True)
class VehicleTable:
    """The vehicles of an episode's start, in placement order, and every group's facts.

    Attributes:
        classes: one entry per vehicle group (``VehicleParams.groups`` order).
        ids: vehicle ids (``{group}_{i}``).
        group: index into ``classes`` of each vehicle.
        start_edges: edge each vehicle enters on.
        start_lane_pos: entry position on that edge, m.
        start_lanes: entry lane.
        initial_speeds: entry speed, m/s.
        routes: SUMO route id of each vehicle (``None``: the start edge's route).
    """

    classes: tuple[VehicleClass, ...]
    ids: list[str]
    group: IntArray
    start_edges: list[str]
    start_lane_pos: list[float]
    start_lanes: list[int]
    initial_speeds: list[float]
    routes: list[str | None]

    @property
    def size(self) -> int:
        """Number of vehicles at the start."""
        return len(self.ids)


class Population:
    """Who is in the network: slot bookkeeping plus compact per-vehicle static arrays.

    Attributes (compact, one entry per live vehicle, in entry order):
        ids, types, group, is_rl, commanded, continuous, lengths, min_gaps, max_speeds,
        accels, decels.
        version: incremented whenever vehicles enter or leave.
        any_continuous: whether any live vehicle is routed by ``ContinuousRouter``.
    """

    def __init__(self, classes: Sequence[VehicleClass]) -> None:
        # the last class stands for vehicles of a vType no group declares (a template's own
        # route file): SUMO drives them, nobody commands them
        self.classes = (*classes, FOREIGN)
        self._by_name = {c.name: i for i, c in enumerate(classes)}
        self.foreign = len(classes)
        cls = self.classes
        # every class's facts as columns of two tables (flags, numbers): a change gathers
        # each table once; the per-vehicle attributes are rows of the gathered tables
        self._c_flags = np.array(
            [[c.is_rl for c in cls], [c.commanded for c in cls], [c.continuous for c in cls],
             [c.lane_controlled for c in cls]], dtype=bool,
        )  # fmt: skip
        self._c_numbers = np.array(
            [[c.length for c in cls], [c.min_gap for c in cls], [c.max_speed for c in cls],
             [c.accel for c in cls], [c.decel for c in cls]], dtype=np.float64,
        )  # fmt: skip
        self._slot_of: dict[str, int] = {}
        #: whether a vehicle id is in the network, as a C-level call (``filter(pop.present,
        #: ids)`` checks many ids without a Python frame per id, as ``in`` needs)
        self.present: Callable[[object], bool] = self._slot_of.__contains__
        self._slot_group = np.zeros(0, dtype=np.int64)
        self._row_of_slot = np.zeros(0, dtype=np.int64)
        self._free: list[int] = []
        self.ids: list[str] = []
        self.slots = np.zeros(0, dtype=np.int64)
        self.version = 0
        self._refresh()

    # ------------------------------------------------------------------ changes
    def class_index(self, type_name: str) -> int:
        """Index of the group whose SUMO vType is ``type_name`` (:attr:`foreign` if none)."""
        return self._by_name.get(type_name, self.foreign)

    def add(self, ids: Sequence[str], groups: Iterable[int]) -> None:
        """Vehicles that entered the network (appended in the given order)."""
        self.change((), ids, groups)

    def remove(self, ids: Iterable[str]) -> None:
        """Vehicles that left the network (unknown ids are ignored)."""
        self.change(ids, (), ())

    def change(
        self, removed: Iterable[str], added: Sequence[str], groups: Iterable[int]
    ) -> IntArray | None:
        """Vehicles that left and vehicles that entered, in one update of the arrays.

        Unknown ids in ``removed`` and known ids in ``added`` are ignored. The survivors
        keep their order and the new vehicles are appended in the given order.

        Returns:
            for each row after the change, its row before (-1 for a vehicle that entered),
            or ``None`` when nothing changed.
        """
        slot_of = self._slot_of
        gone = [slot_of.pop(vid) for vid in removed if vid in slot_of]
        new_slots: list[int] = []
        new_ids: list[str] = []
        for vid, g in zip(added, groups, strict=True):
            if vid in slot_of:
                continue
            slot = self._free.pop() if self._free else self._grow()
            slot_of[vid] = slot
            self._slot_group[slot] = g
            new_slots.append(slot)
            new_ids.append(vid)
        if not gone and not new_ids:
            return None
        n = len(self.ids)
        if gone:
            self._free.extend(gone)
            mask = np.ones(n, dtype=bool)
            mask[self._row_of_slot[gone]] = False
            kept = mask.nonzero()[0]  # (np.flatnonzero adds a Python layer)
            self.ids = list(compress(self.ids, mask.tolist()))  # a new list: frames keep theirs
            old_slots = self.slots[kept]
        else:
            kept = np.arange(n)
            self.ids = list(self.ids)
            old_slots = self.slots
        self.ids += new_ids
        self.slots = np.concatenate((old_slots, np.array(new_slots, dtype=np.int64)))
        self._refresh()
        return np.concatenate((kept, np.full(len(new_ids), -1, dtype=np.int64)))

    def _grow(self) -> int:
        slot = self._slot_group.size
        cap = max(16, 2 * slot)
        self._slot_group = np.concatenate((self._slot_group, np.zeros(cap - slot, np.int64)))
        self._row_of_slot = np.concatenate((self._row_of_slot, np.full(cap - slot, -1)))
        self._free.extend(range(cap - 1, slot, -1))
        return slot

    def _refresh(self) -> None:
        self.version += 1
        self._row_of_slot[self.slots] = np.arange(self.slots.size)
        g = self._slot_group[self.slots]
        self.group = g
        self._types: tuple[int, list[str]] | None = None
        # (take along axis 1: a third of the time of fancy indexing [:, g])
        self.is_rl, self.commanded, self.continuous, self.lane_controlled = self._c_flags.take(
            g, axis=1
        )
        self.lengths, self.min_gaps, self.max_speeds, self.accels, self.decels = (
            self._c_numbers.take(g, axis=1)
        )
        self.any_continuous = bool(np.count_nonzero(self.continuous))  # .any(): a Python layer

    # ------------------------------------------------------------------ lookups
    @property
    def types(self) -> list[str]:
        """Group (vType) name of every live vehicle; built when first asked after a change."""
        if self._types is None or self._types[0] != self.version:
            names = [c.name for c in self.classes]
            self._types = (self.version, [names[i] for i in self.group.tolist()])
        return self._types[1]

    @property
    def size(self) -> int:
        """Number of vehicles in the network."""
        return len(self.ids)

    def __contains__(self, veh_id: object) -> bool:
        return veh_id in self._slot_of

    def row(self, veh_id: str) -> int:
        """Row of ``veh_id`` in the compact arrays.

        Raises:
            KeyError: the vehicle is not in the network.
        """
        return int(self._row_of_slot[self._slot_of[veh_id]])

    def rows(self, veh_ids: Iterable[str]) -> IntArray:
        """Rows of several vehicles (``KeyError`` for one not in the network)."""
        slot_of = self._slot_of
        slots = np.fromiter((slot_of[v] for v in veh_ids), np.int64)
        return self._row_of_slot[slots]

    def rows_of_group(self, group: int) -> IntArray:
        """Rows of the live vehicles of one group, in entry order."""
        return np.flatnonzero(self.group == group)
