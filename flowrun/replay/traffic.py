"""Traffic on a road over time: speed and density of the cars on it, outflow per minute."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flowrun.recording import McapLog
from flowrun.recording.frames import StepStats
from flowrun.replay.route import RouteLayout, network_length
from flowrun.types import FloatArray, IntArray


@dataclass(frozen=True)
class TrafficSeries:
    """Per logged step: the cars on a road (a route, or the whole network).

    Attributes:
        times: simulation time of each logged step, s.
        count: cars on the road.
        mean_speed: their mean speed, m/s (``nan`` without cars).
        min_speed: their lowest speed, m/s.
        max_speed: their highest speed, m/s.
        density: cars per km of road, all lanes together (``nan`` when the road's length is
            unknown).
        road: what the numbers cover (a route ``a → b``, or ``network``).
        length: the road's length, m.
    """

    times: FloatArray
    count: IntArray
    mean_speed: FloatArray
    min_speed: FloatArray
    max_speed: FloatArray
    density: FloatArray
    road: str
    length: float


def traffic_series(
    log: McapLog,
    route: RouteLayout | None = None,
    *,
    start_s: float | None = None,
    end_s: float | None = None,
) -> TrafficSeries:
    """Speed and density over time on ``route`` (its edges and the junctions between them),
    or over the whole network when ``route`` is ``None``."""
    times: list[float] = []
    rows: list[tuple[float, float, float, float]] = []
    nan = math.nan
    for msg in log.vehicle_messages(start_s, end_s):
        speed = np.array(msg.speed, dtype=np.float64)
        if route is not None:
            on, _ = route.locate(list(msg.edges), np.array(msg.lane_pos, dtype=np.float64))
            speed = speed[on]
        times.append(msg.time)
        if speed.size:
            rows.append((speed.size, speed.mean(), speed.min(), speed.max()))
        else:
            rows.append((0, nan, nan, nan))
    table = np.array(rows, dtype=np.float64).reshape(-1, 4)
    length = route.length if route is not None else network_length(log)
    count = table[:, 0]
    return TrafficSeries(
        times=np.array(times, dtype=np.float64),
        count=count.astype(np.int64),
        mean_speed=table[:, 1],
        min_speed=table[:, 2],
        max_speed=table[:, 3],
        density=count / (length / 1000.0) if length > 0 else np.full(count.size, nan),
        road=route.label if route is not None else "network",
        length=length,
    )


@dataclass(frozen=True)
class Outflow:
    """Vehicles leaving the network, per time bin.

    Attributes:
        start: start of each bin, s.
        count: vehicles that left in the bin.
        covered: simulated time the bin's logged steps cover, s (a full bin: its width).
        rate: ``count`` per hour of ``covered``, veh/h.
    """

    start: FloatArray
    count: IntArray
    covered: FloatArray
    rate: FloatArray


def outflow(stats: Sequence[StepStats], bin_s: float = 60.0) -> Outflow:
    """Outflow per ``bin_s`` seconds (per minute by default) from ``/flowrun/stats``.

    A logged step belongs to the bin ``[t0 + k * bin_s, t0 + (k + 1) * bin_s)`` that holds its
    time (``t0``: the first logged step's); its ``arrived`` count (vehicles that left since
    the previous logged step) goes to that bin. Each logged step covers the median interval
    between logged steps, so a last, partial bin gives a rate over the time it covers.

    Args:
        stats: the logged steps, in time order.
        bin_s: bin width, s.
    """
    if not stats:
        empty = np.zeros(0)
        return Outflow(empty, np.zeros(0, dtype=np.int64), empty, empty)
    t = np.array([s.time for s in stats], dtype=np.float64)
    arrived = np.array([s.arrived for s in stats], dtype=np.int64)
    interval = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    # a hair of slack so that a step exactly on a bin edge is not lost to rounding
    index = np.floor((t - t[0]) / bin_s + 1e-9).astype(np.int64)
    bins = int(index[-1]) + 1
    count = np.bincount(index, weights=arrived, minlength=bins).astype(np.int64)
    covered = (np.bincount(index, minlength=bins) * interval).astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        rate = np.where(covered > 0, count * 3600.0 / covered, math.nan)
    return Outflow(t[0] + bin_s * np.arange(bins), count, covered, rate)
