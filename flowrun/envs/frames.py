"""Copy the kernel's per-step snapshot into the log's frame types."""

from __future__ import annotations

import math

import numpy as np

from flowrun.kernel import Kernel
from flowrun.recording.frames import StepStats, VehicleFrame


def snapshot_frame(k: Kernel, step: int) -> VehicleFrame:
    """Every vehicle's state at the current step, as a :class:`VehicleFrame`.

    The arrays are the kernel's own: it replaces them every step instead of writing into them,
    so a frame stays valid without copies (treat it as read-only).
    """
    vk = k.vehicle
    return VehicleFrame(
        step=step,
        time=k.simulation.time,
        ids=vk.table.ids,
        types=vk.table.types,
        edges=vk.edges,
        lanes=vk.lanes,
        lane_pos=vk.lane_pos,
        position=vk.position,
        odometer=vk.odometer,
        x=vk.x,
        y=vk.y,
        speed=vk.speed,
        accel_cmd=vk.last_cmd,
        accel_real=vk.accel_real,
        headway=vk.headway,
        leader=vk.leader_ids(),
        is_rl=vk.table.is_rl,
    )


def snapshot_stats(k: Kernel, step: int, reward: float) -> StepStats:
    """Aggregates of the current step."""
    speed = k.vehicle.speed
    n = int(speed.size)
    sim = k.simulation
    if not n:
        nan = math.nan
        return StepStats(step, sim.time, 0, nan, nan, nan, nan, reward, sim.step_collisions,
                         sim.step_teleports)  # fmt: skip
    # The same operations, in the same order, as numpy's mean and std: bit-identical results
    # without their per-call overhead.
    mean = _add(speed) / n
    dev = speed - mean
    std = math.sqrt(_add(dev * dev) / n)
    return StepStats(
        step, sim.time, n, float(mean), float(_min(speed)), float(_max(speed)), std, reward,
        sim.step_collisions, sim.step_teleports,
    )  # fmt: skip


_add = np.add.reduce
_min = np.minimum.reduce
_max = np.maximum.reduce


def with_reward(stats: StepStats, reward: float) -> StepStats:
    """``stats`` with its reward set (a plain constructor call: cheaper than ``replace``)."""
    s = stats
    return StepStats(
        s.step, s.time, s.num_vehicles, s.mean_speed, s.min_speed, s.max_speed, s.speed_std,
        reward, s.collisions, s.teleports,
    )  # fmt: skip
