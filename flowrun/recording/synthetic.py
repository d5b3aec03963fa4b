"""Synthetic ring traffic with a travelling slow zone, for tests and benchmarks (no SUMO).

Each car drives at ``v_free - dip * exp(-(d / width)^2)`` where ``d`` is its distance to the
centre of a slow zone that moves around the ring at ``wave_speed`` (negative = against the
traffic, like a stop-and-go wave). Positions are integrated with Euler steps.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from flowrun.recording.frames import StepStats, VehicleFrame
from flowrun.types import FloatArray

VEHICLE_LENGTH = 5.0


def step_stats(
    frame: VehicleFrame, reward: float = math.nan, collisions: int = 0, teleports: int = 0
) -> StepStats:
    """Aggregates of ``frame`` (population std across vehicles)."""
    speed = frame.speed
    empty = speed.size == 0
    return StepStats(
        step=frame.step,
        time=frame.time,
        num_vehicles=len(frame.ids),
        mean_speed=math.nan if empty else float(speed.mean()),
        min_speed=math.nan if empty else float(speed.min()),
        max_speed=math.nan if empty else float(speed.max()),
        speed_std=math.nan if empty else float(speed.std()),
        reward=reward,
        collisions=collisions,
        teleports=teleports,
    )


def ring_frames(
    num_vehicles: int = 22,
    steps: int = 300,
    *,
    ring_length: float = 230.0,
    dt: float = 0.1,
    wave_speed: float = -4.0,
    v_free: float = 6.0,
    dip: float = 5.0,
    width: float = 25.0,
    num_rl: int = 1,
    num_edges: int = 4,
) -> Iterator[tuple[VehicleFrame, StepStats]]:
    """Yield ``steps`` frames (step 0 at t=0) of ``num_vehicles`` cars on a ring.

    Args:
        num_vehicles: cars on the ring; the first ``num_rl`` are RL cars (type ``rl``).
        steps: number of frames.
        ring_length: ring circumference, m.
        dt: step length, s.
        wave_speed: speed of the slow zone's centre around the ring, m/s.
        v_free: speed outside the slow zone, m/s.
        dip: speed reduction at the slow zone's centre, m/s.
        width: e-folding half-width of the slow zone, m.
        num_rl: number of RL cars.
        num_edges: the ring is split into this many equal edges.
    """
    n = num_vehicles
    ids = [f"{'rl' if i < num_rl else 'idm'}_{i}" for i in range(n)]
    types = ["rl" if i < num_rl else "idm" for i in range(n)]
    is_rl = np.arange(n) < num_rl
    leaders = [ids[(i + 1) % n] for i in range(n)]
    edge_names = [f"e{k}" for k in range(num_edges)]
    edge_len = ring_length / num_edges
    pos: FloatArray = np.arange(n, dtype=np.float64) * (ring_length / n)
    odometer: FloatArray = np.zeros(n)
    prev_speed: np.ndarray | None = None
    radius = ring_length / (2 * math.pi)
    for step in range(steps):
        t = step * dt
        centre = (ring_length / 2 + wave_speed * t) % ring_length
        d = (pos - centre + ring_length / 2) % ring_length - ring_length / 2
        speed = v_free - dip * np.exp(-((d / width) ** 2))
        accel = np.zeros(n) if prev_speed is None else (speed - prev_speed) / dt
        gap = (np.roll(pos, -1) - pos) % ring_length - VEHICLE_LENGTH
        edge_idx = np.minimum((pos // edge_len).astype(np.int64), num_edges - 1)
        angle = pos / radius
        frame = VehicleFrame(
            step=step,
            time=t,
            ids=ids,
            types=types,
            edges=[edge_names[k] for k in edge_idx],
            lanes=np.zeros(n, dtype=np.int64),
            lane_pos=pos - edge_idx * edge_len,
            position=pos.copy(),
            odometer=odometer.copy(),
            x=radius * np.cos(angle),
            y=radius * np.sin(angle),
            speed=speed,
            accel_cmd=accel.copy(),
            accel_real=accel,
            headway=gap,
            leader=leaders,
            is_rl=is_rl,
        )
        reward = float(speed.mean()) if num_rl else math.nan
        yield frame, step_stats(frame, reward=reward)
        prev_speed = speed
        pos = (pos + speed * dt) % ring_length
        odometer = odometer + speed * dt
