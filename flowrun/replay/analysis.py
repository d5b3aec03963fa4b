"""Pure data behind the replay summary and plots: speed series, time-space points, wave drift."""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flowrun.recording import McapLog
from flowrun.replay.route import RouteLayout
from flowrun.types import FloatArray

StrArray = np.ndarray


@dataclass(frozen=True)
class SpeedSeries:
    """Per-logged-step speed aggregates over the selected vehicles.

    Attributes:
        times: simulation time of each logged step, s.
        steps: simulation step index of each logged step.
        mean: mean speed across vehicles, m/s.
        min: minimum speed across vehicles, m/s.
        max: maximum speed across vehicles, m/s.
        std: population standard deviation of speed across vehicles, m/s.
        count: vehicles in the step.
        vehicle_types: vehicle id -> type, for every vehicle seen.
        rl_ids: ids of RL-driven vehicles seen.
    """

    times: FloatArray
    steps: np.ndarray
    mean: FloatArray
    min: FloatArray
    max: FloatArray
    std: FloatArray
    count: np.ndarray
    vehicle_types: dict[str, str] = field(default_factory=dict)
    rl_ids: frozenset[str] = frozenset()


def _with_rosters(messages: Iterable[Any], every: int = 1) -> Iterator[tuple[Any, bool]]:
    """Every ``every``-th vehicle message, each with whether its roster (ids, types, RL flags)
    may differ from the previous one's: the writer bumps ``roster_version`` when it changes,
    and version 0 means each message has its own."""
    last_roster = -1
    for k, msg in enumerate(messages):
        if k % every:
            continue
        roster = msg.roster_version
        yield msg, roster == 0 or roster != last_roster
        last_roster = roster


def _keep_indices(ids: list[str], wanted: set[str] | None) -> list[int] | None:
    if wanted is None:
        return None
    return [i for i, vid in enumerate(ids) if vid in wanted]


def speed_series(
    log: McapLog,
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
) -> SpeedSeries:
    """One pass over the vehicle frames computing per-step speed aggregates.

    Reads only the ``speed``, ``ids``, ``types`` and ``is_rl`` columns; steps without any
    selected vehicle get ``nan`` aggregates and count 0.
    """
    wanted = None if vehicles is None else set(vehicles)
    times: list[float] = []
    steps: list[int] = []
    rows: list[tuple[float, float, float, float, int]] = []
    types: dict[str, str] = {}
    rl_ids: set[str] = set()
    last_ids: list[str] | None = None
    keep: list[int] | None = None
    nan = math.nan
    for msg, new_roster in _with_rosters(log.vehicle_messages(start_s, end_s)):
        if new_roster:
            ids = list(msg.ids)
            vtypes = list(msg.types)
            is_rl = list(msg.is_rl)
            if ids != last_ids:
                keep = _keep_indices(ids, wanted)
                last_ids = ids
            for i in range(len(ids)) if keep is None else keep:
                types[ids[i]] = vtypes[i]
                if is_rl[i]:
                    rl_ids.add(ids[i])
        speed = np.array(msg.speed, dtype=np.float64)
        if keep is not None:
            speed = speed[keep]
        times.append(msg.time)
        steps.append(msg.step)
        if speed.size:
            rows.append((speed.mean(), speed.min(), speed.max(), speed.std(), speed.size))
        else:
            rows.append((nan, nan, nan, nan, 0))
    table = np.array(rows, dtype=np.float64).reshape(-1, 5)
    return SpeedSeries(
        times=np.array(times, dtype=np.float64),
        steps=np.array(steps, dtype=np.int64),
        mean=table[:, 0],
        min=table[:, 1],
        max=table[:, 2],
        std=table[:, 3],
        count=table[:, 4].astype(np.int64),
        vehicle_types=types,
        rl_ids=frozenset(rl_ids),
    )


@dataclass(frozen=True)
class TimeSpace:
    """Flattened (one entry per vehicle per logged step) points of a time-space diagram."""

    times: FloatArray
    positions: FloatArray
    speeds: FloatArray
    ids: StrArray
    is_rl: np.ndarray


#: One logged step's points: times, positions, speeds, ids, RL flags.
_StepPoints = tuple[FloatArray, FloatArray, FloatArray, StrArray, np.ndarray]


def time_space_points(
    log: McapLog,
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
    every: int = 1,
    route: RouteLayout | None = None,
) -> TimeSpace:
    """Time-space points, reading every ``every``-th logged step.

    Args:
        log: an opened log.
        start_s: first simulation time to read, s.
        end_s: last simulation time to read, s.
        vehicles: only these vehicle ids (``None``: all).
        every: read every n-th logged step.
        route: positions along this route, and only the cars on it (its edges and the
            junctions between them); ``None``: the logged network position of every car
            (the ring position on a ring).
    """
    if route is not None:
        return _route_points(log, route, start_s, end_s, vehicles, every)
    wanted = None if vehicles is None else set(vehicles)
    steps: list[_StepPoints] = []
    last_ids: list[str] | None = None
    keep: list[int] | None = None
    id_arr = np.array([], dtype=str)
    for msg, new_roster in _with_rosters(log.vehicle_messages(start_s, end_s), every):
        if new_roster:
            ids = list(msg.ids)
            if ids != last_ids:
                keep = _keep_indices(ids, wanted)
                id_arr = np.array(ids if keep is None else [ids[i] for i in keep], dtype=str)
                last_ids = ids
        pos = np.array(msg.position, dtype=np.float64)
        speed = np.array(msg.speed, dtype=np.float64)
        rl = np.array(msg.is_rl, dtype=np.bool_)
        if keep is not None:
            pos, speed, rl = pos[keep], speed[keep], rl[keep]
        steps.append((np.full(pos.size, msg.time), pos, speed, id_arr, rl))
    return _joined(steps)


def _route_points(
    log: McapLog,
    route: RouteLayout,
    start_s: float | None,
    end_s: float | None,
    vehicles: Iterable[str] | None,
    every: int,
) -> TimeSpace:
    """:func:`time_space_points` along a route: the car set differs from step to step."""
    wanted = None if vehicles is None else set(vehicles)
    steps: list[_StepPoints] = []
    ids: list[str] = []
    for msg, new_roster in _with_rosters(log.vehicle_messages(start_s, end_s), every):
        if new_roster:
            ids = list(msg.ids)
        on, pos = route.locate(list(msg.edges), np.array(msg.lane_pos, dtype=np.float64))
        if wanted is not None:
            keep = np.array([ids[i] in wanted for i in on.tolist()], dtype=np.bool_)
            on, pos = on[keep], pos[keep]
        speed = np.array(msg.speed, dtype=np.float64)[on]
        id_arr = np.array([ids[i] for i in on.tolist()], dtype=str)
        rl = np.array(msg.is_rl, dtype=np.bool_)[on]
        steps.append((np.full(pos.size, msg.time), pos, speed, id_arr, rl))
    return _joined(steps)


def _joined(steps: list[_StepPoints]) -> TimeSpace:
    """The steps' points, concatenated column by column."""
    dtypes: tuple[type, ...] = (np.float64, np.float64, np.float64, str, np.bool_)
    columns = [
        np.concatenate([step[c] for step in steps]) if steps else np.array([], dtype=dtype)
        for c, dtype in enumerate(dtypes)
    ]
    times, positions, speeds, ids, is_rl = columns
    return TimeSpace(times=times, positions=positions, speeds=speeds, ids=ids, is_rl=is_rl)


def time_space_data(
    log: McapLog,
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray, StrArray]:
    """``(times, positions, speeds, ids)``: one entry per vehicle per logged step (s, m, m/s)."""
    ts = time_space_points(log, start_s=start_s, end_s=end_s, vehicles=vehicles)
    return ts.times, ts.positions, ts.speeds, ts.ids


def wave_drift(
    times: FloatArray,
    positions: FloatArray,
    speeds: FloatArray,
    ring_length: float,
    max_harmonic: int = 4,
    grid_points: int = 256,
) -> float:
    """Estimated speed at which the slow zone (the speed minimum) travels around the ring.

    At each logged time the cars' speeds are interpolated (periodically) onto a uniform grid
    around the ring, so that bunched cars do not bias the estimate; the "slowness"
    ``max(v) - v`` on that grid is decomposed into circular harmonics, and the phase of the
    dominant one (``k`` stop-and-go waves on the ring) locates the slow zone(s). The
    unwrapped phase is fitted linearly against time. Works on flattened points as returned
    by :func:`time_space_data`.

    Args:
        times: simulation time of each point, s.
        positions: ring position of each point, m.
        speeds: speed of each point, m/s.
        ring_length: ring circumference, m.
        max_harmonic: largest number of waves considered.
        grid_points: resolution of the interpolation grid.

    Returns:
        drift in m/s in the ring's position coordinate (negative = moving backwards, against
        the traffic); ``nan`` if there is no speed variation to track.
    """
    t = np.asarray(times, dtype=np.float64)
    x = np.asarray(positions, dtype=np.float64) % ring_length
    v = np.asarray(speeds, dtype=np.float64)
    ok = np.isfinite(t) & np.isfinite(x) & np.isfinite(v)
    t, x, v = t[ok], x[ok], v[ok]
    order = np.lexsort((x, t))
    t, x, v = t[order], x[order], v[order]
    uniq, first = np.unique(t, return_index=True)
    bounds = [*first.tolist(), t.size]
    grid = np.arange(grid_points) * (ring_length / grid_points)
    rows: list[FloatArray] = []
    row_times: list[float] = []
    for i, t_i in enumerate(uniq.tolist()):
        lo, hi = bounds[i], bounds[i + 1]
        if hi - lo < 3:
            continue
        profile = np.interp(grid, x[lo:hi], v[lo:hi], period=ring_length)
        rows.append(profile.max() - profile)
        row_times.append(t_i)
    if len(rows) < 2:
        return math.nan
    slowness = np.array(rows)
    harmonics = np.arange(1, max_harmonic + 1)
    basis = np.exp(1j * np.outer(2 * np.pi * grid / ring_length, harmonics))
    z = slowness @ basis  # (times, harmonics)
    k_index = int(np.argmax(np.abs(z).sum(axis=0)))
    zk = z[:, k_index]
    total = slowness.sum(axis=1)
    valid = (total > 1e-9) & (np.abs(zk) > 1e-6 * np.maximum(total, 1e-12))
    if valid.sum() < 2:
        return math.nan
    phase = np.unwrap(np.angle(zk[valid]))
    slope = np.polyfit(np.array(row_times)[valid], phase, 1)[0]
    return float(slope * ring_length / (2 * np.pi * harmonics[k_index]))
