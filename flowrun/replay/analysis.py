"""Pure data behind the replay summary and plots: speed series, time-space points, wave drift."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from flowrun.recording import McapLog
from flowrun.recording.frames import FloatArray

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
    for msg in log.vehicle_messages(start_s, end_s):
        ids = list(msg.ids)
        if ids != last_ids:
            keep = _keep_indices(ids, wanted)
            vtypes = list(msg.types)
            is_rl = list(msg.is_rl)
            for i in range(len(ids)) if keep is None else keep:
                types[ids[i]] = vtypes[i]
                if is_rl[i]:
                    rl_ids.add(ids[i])
            last_ids = ids
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


def time_space_points(
    log: McapLog,
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
    every: int = 1,
) -> TimeSpace:
    """Time-space points, reading every ``every``-th logged step."""
    wanted = None if vehicles is None else set(vehicles)
    t_parts, p_parts, v_parts, id_parts, rl_parts = [], [], [], [], []
    last_ids: list[str] | None = None
    keep: list[int] | None = None
    id_arr = np.array([], dtype=str)
    for k, msg in enumerate(log.vehicle_messages(start_s, end_s)):
        if k % every:
            continue
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
        t_parts.append(np.full(pos.size, msg.time))
        p_parts.append(pos)
        v_parts.append(speed)
        id_parts.append(id_arr)
        rl_parts.append(rl)

    def cat(parts: list[np.ndarray], dtype: type) -> np.ndarray:
        return np.concatenate(parts) if parts else np.array([], dtype=dtype)

    return TimeSpace(
        times=cat(t_parts, np.float64),
        positions=cat(p_parts, np.float64),
        speeds=cat(v_parts, np.float64),
        ids=cat(id_parts, str),
        is_rl=cat(rl_parts, np.bool_),
    )


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
) -> float:
    """Estimated speed at which the slow zone (the speed minimum) travels around the ring.

    For each logged time the "slowness" ``max(v) - v`` of every car is a weight on its
    angle around the ring; the phase of the dominant circular harmonic of that weight
    (``k`` stop-and-go waves on the ring) locates the slow zone(s). The unwrapped phase is
    fitted linearly against time. Works on flattened points as returned by
    :func:`time_space_data`.

    Args:
        times: simulation time of each point, s.
        positions: ring position of each point, m.
        speeds: speed of each point, m/s.
        ring_length: ring circumference, m.
        max_harmonic: largest number of waves considered.

    Returns:
        drift in m/s in the ring's position coordinate (negative = moving backwards, against
        the traffic); ``nan`` if there is no speed variation to track.
    """
    t = np.asarray(times, dtype=np.float64)
    theta = 2 * np.pi * (np.asarray(positions, dtype=np.float64) % ring_length) / ring_length
    v = np.asarray(speeds, dtype=np.float64)
    ok = np.isfinite(t) & np.isfinite(theta) & np.isfinite(v)
    t, theta, v = t[ok], theta[ok], v[ok]
    if t.size == 0:
        return math.nan
    uniq, inverse = np.unique(t, return_inverse=True)
    vmax = np.zeros(uniq.size)
    np.maximum.at(vmax, inverse, v)
    weight = vmax[inverse] - v
    strength = np.zeros(max_harmonic)
    sums = []
    for k in range(1, max_harmonic + 1):
        z = np.zeros(uniq.size, dtype=np.complex128)
        np.add.at(z, inverse, weight * np.exp(1j * k * theta))
        sums.append(z)
        strength[k - 1] = np.abs(z).sum()
    k_best = int(np.argmax(strength)) + 1
    z = sums[k_best - 1]
    total = np.zeros(uniq.size)
    np.add.at(total, inverse, weight)
    valid = (total > 1e-9) & (np.abs(z) > 1e-6 * np.maximum(total, 1e-12))
    if valid.sum() < 2:
        return math.nan
    phase = np.unwrap(np.angle(z[valid]))
    slope = np.polyfit(uniq[valid], phase, 1)[0]
    return float(slope * ring_length / (2 * np.pi * k_best))
