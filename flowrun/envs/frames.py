"""Copy the kernel's per-step snapshot into step records, frames and per-step statistics."""

from __future__ import annotations

import json
import math
import weakref
from dataclasses import dataclass
from itertools import groupby

import numpy as np

from flowrun.kernel import Kernel
from flowrun.kernel.geometry import RingPlacement
from flowrun.kernel.population import Population
from flowrun.recording.frames import SignalFrame, StepStats, VehicleFrame
from flowrun.types import FloatArray, IntArray


def snapshot_frame(k: Kernel, step: int, deferred: bool = False) -> VehicleFrame:
    """Every vehicle's state at the current step, as a :class:`VehicleFrame`.

    The arrays are the kernel's own: it replaces them every step instead of writing into them,
    so a frame stays valid without copies (treat it as read-only). ``deferred`` leaves
    ``edges``, ``lane_pos``, ``x``, ``y`` and ``accel_real`` empty, for :func:`complete_frames`
    to derive for a whole batch of steps at once.
    """
    vk = k.vehicle
    if deferred:
        edges, lane_pos, x, y, accel_real = [], _EMPTY, _EMPTY, _EMPTY, _EMPTY
    else:
        edges, lane_pos, x, y, accel_real = vk.edges, vk.lane_pos, vk.x, vk.y, vk.accel_real
    return VehicleFrame(
        step=step,
        time=k.simulation.time,
        ids=_frozen_ids(vk.table),
        types=vk.table.types,
        edges=edges,
        lanes=vk.lanes,
        lane_pos=lane_pos,
        position=vk.position,
        odometer=vk.odometer,
        x=x,
        y=y,
        speed=vk.speed,
        accel_cmd=vk.last_cmd,
        accel_real=accel_real,
        headway=vk.headway,
        leader=vk.leader_ids(),
        is_rl=vk.table.is_rl,
    )


_EMPTY = np.zeros(0)


def snapshot_signals(k: Kernel, step: int) -> SignalFrame | None:
    """Every traffic light's state, phase and program at the current step (``None`` on a
    network without lights). Copies: the kernel updates its lists in place each step."""
    tk = k.traffic_light
    if not tk.states:
        return None
    return SignalFrame(
        step=step,
        time=k.simulation.time,
        ids=tk.get_ids(),
        states=list(tk.states),
        phases=tk.phases.copy(),
        programs=list(tk.programs),
    )


#: population -> (its version, a private copy of its ids at that version)
_ID_COPIES: weakref.WeakKeyDictionary[Population, tuple[int, list[str]]] = (
    weakref.WeakKeyDictionary()
)


def _frozen_ids(pop: Population) -> list[str]:
    """The population's ids as a list nobody changes later, copied once per roster.

    The population may append to its own ``ids`` list in place when cars enter, which would
    change the ids of frames still queued; frames hold this copy instead. Between changes
    every frame gets the same list object, which keeps the recorder's identity checks cheap.
    """
    version = pop.version
    cached = _ID_COPIES.get(pop)
    if cached is not None and cached[0] == version:
        return cached[1]
    ids = list(pop.ids)
    _ID_COPIES[pop] = (version, ids)
    return ids


def complete_frames(records: list[StepRecord], placement: RingPlacement, dt: float) -> None:
    """Fill in what :func:`snapshot_frame` deferred, for every framed record, in place.

    The same formulas as the kernel's per-step getters, on all steps at once: edge and lane
    position from the ring position, map coordinates from the lane shapes, and the realised
    acceleration ``(v - v_previous) / dt``.
    """
    framed = [r for r in records if r.frame is not None and r.prev_speed is not None]
    if not framed:
        return
    if len({r.speed.size for r in framed}) > 1:  # vehicles came or went: one step at a time
        for r in framed:
            complete_frames([r], placement, dt)
        return
    frames = [r.frame for r in framed if r.frame is not None]
    position = np.stack([f.position for f in frames])
    edge, lane_pos = placement.edges.locate(position)
    lanes = np.stack([f.lanes for f in frames])
    x, y = placement.geometry.xy(edge, lanes, lane_pos)
    speed = np.stack([r.speed for r in framed])
    prev = np.stack([r.prev_speed for r in framed if r.prev_speed is not None])
    accel = (speed - prev) / dt
    names = placement.edges.edge_names(edge)
    for k, f in enumerate(frames):
        f.edges, f.lane_pos, f.x, f.y, f.accel_real = names[k], lane_pos[k], x[k], y[k], accel[k]


@dataclass(slots=True)
class StepRecord:
    """One simulation step as the environment queues it: raw values, aggregated later.

    Attributes:
        step: simulation step index since the episode started.
        time: simulation time, s.
        speed: every vehicle's speed, m/s (the kernel's array: never written into).
        collisions: collisions SUMO reported in this step.
        teleports: teleports SUMO started in this step.
        frame: the full vehicle frame when recording, else ``None``.
        reward: reward of the RL step this simulation step belongs to (set by ``Env.step``).
        prev_speed: the speeds of the step before, kept while the frame is incomplete.
        departed: vehicles that entered the network in this step.
        arrived: vehicles that left the network in this step.
        signals: the traffic lights' states when recording on a network with lights.
        lane_changes: cars that changed lane in this step (multi-lane networks; same edge,
            another lane).
    """

    step: int
    time: float
    speed: FloatArray
    collisions: int
    teleports: int
    frame: VehicleFrame | None
    reward: float = math.nan
    prev_speed: FloatArray | None = None
    departed: int = 0
    arrived: int = 0
    signals: SignalFrame | None = None
    lane_changes: int = 0


def step_record(k: Kernel, step: int, with_frame: bool, deferred: bool = False) -> StepRecord:
    """The current step's record (and frame, when asked; see :func:`snapshot_frame`)."""
    sim = k.simulation
    vk = k.vehicle
    frame = snapshot_frame(k, step, deferred) if with_frame else None
    prev = vk.prev_speed if with_frame and deferred else None
    return StepRecord(
        step, sim.time, vk.speed, sim.step_collisions, sim.step_teleports, frame, math.nan, prev,
        len(vk.departed_ids), len(vk.arrived_ids),
        snapshot_signals(k, step) if with_frame else None,
        len(vk.lane_change_log().changed) if vk.multi_lane else 0,
    )  # fmt: skip


@dataclass(frozen=True)
class StatsBatch:
    """Per-step aggregates of consecutive records, one array entry per step (speeds in m/s)."""

    step: IntArray
    time: FloatArray
    num_vehicles: IntArray
    mean_speed: FloatArray
    min_speed: FloatArray
    max_speed: FloatArray
    speed_std: FloatArray
    reward: FloatArray
    collisions: IntArray
    teleports: IntArray
    departed: IntArray
    arrived: IntArray
    lane_changes: IntArray

    def __len__(self) -> int:
        return int(self.step.size)

    def rows(self) -> list[StepStats]:
        """The batch as :class:`StepStats` objects, step by step."""
        columns = (
            self.step, self.time, self.num_vehicles, self.mean_speed, self.min_speed,
            self.max_speed, self.speed_std, self.reward, self.collisions, self.teleports,
            self.departed, self.arrived, self.lane_changes,
        )  # fmt: skip
        return [StepStats(*row) for row in zip(*(c.tolist() for c in columns), strict=True)]


def batch_stats(records: list[StepRecord]) -> StatsBatch:
    """Count, mean, min, max and population standard deviation of speed for every record.

    Consecutive records with the same number of vehicles (all of them, on a ring) are
    aggregated together, one numpy call per statistic. Steps without vehicles get ``nan``.
    """
    parts = [
        _speed_aggregates(np.stack([r.speed for r in group]))
        for _, group in groupby(records, key=lambda r: r.speed.size)
    ]
    count, mean, low, high, std = (np.concatenate(column) for column in zip(*parts, strict=True))
    return StatsBatch(
        np.array([r.step for r in records], dtype=np.int64),
        np.array([r.time for r in records], dtype=np.float64),
        count,
        mean,
        low,
        high,
        std,
        np.array([r.reward for r in records], dtype=np.float64),
        np.array([r.collisions for r in records], dtype=np.int64),
        np.array([r.teleports for r in records], dtype=np.int64),
        np.array([r.departed for r in records], dtype=np.int64),
        np.array([r.arrived for r in records], dtype=np.int64),
        np.array([r.lane_changes for r in records], dtype=np.int64),
    )


def _speed_aggregates(speed: FloatArray) -> tuple[np.ndarray, ...]:
    """Per row of ``speed`` (steps x vehicles, m/s): count, mean, min, max, std."""
    steps, n = speed.shape
    if not n:
        nan = np.full(steps, math.nan)
        return np.zeros(steps, dtype=np.int64), nan, nan, nan, nan
    mean = np.add.reduce(speed, axis=1) / n
    dev = speed - mean[:, None]
    return (
        np.full(steps, n, dtype=np.int64),
        mean,
        np.minimum.reduce(speed, axis=1),
        np.maximum.reduce(speed, axis=1),
        np.sqrt(np.add.reduce(dev * dev, axis=1) / n),
    )


def network_metadata(k: Kernel) -> dict[str, str]:
    """Facts about the episode's network that a log needs to be plotted on its own.

    ``main_route``: the network's main road (JSON list of edges; time-space diagrams follow
    it), ``edge_starts``: every edge's start along the network (JSON object, m; internal
    edges included, Flow's ``total_edgestarts_dict``), ``network_closed``: ``true`` on a ring,
    ``network_length``: m. Call after ``reset``.
    """
    net = k.network
    spec = net.spec
    return {
        "main_route": json.dumps(list(spec.main_route)),
        "edge_starts": json.dumps(net.total_edgestarts_dict),
        "network_closed": "true" if spec.closed else "false",
        "network_length": repr(float(spec.length)),
    }
