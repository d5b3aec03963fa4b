"""Copy the kernel's per-step snapshot into the log's frame types."""

from __future__ import annotations

import math

import numpy as np

from flowrun.kernel import Kernel
from flowrun.recording.frames import StepStats, VehicleFrame


def snapshot_frame(k: Kernel, step: int) -> VehicleFrame:
    """Every vehicle's state at the current step, as a :class:`VehicleFrame`."""
    vk = k.vehicle
    ids = vk.table.ids
    leader = [ids[j] if j >= 0 else "" for j in vk.leader.tolist()]
    return VehicleFrame(
        step=step,
        time=k.simulation.time,
        ids=list(ids),
        types=list(vk.table.types),
        edges=list(vk.edges),
        lanes=vk.lanes.copy(),
        lane_pos=vk.lane_pos.copy(),
        position=vk.position.copy(),
        odometer=vk.odometer.copy(),
        x=vk.x.copy(),
        y=vk.y.copy(),
        speed=vk.speed.copy(),
        accel_cmd=vk.last_cmd.copy(),
        accel_real=vk.accel_real.copy(),
        headway=vk.headway.copy(),
        leader=leader,
        is_rl=vk.table.is_rl.copy(),
    )


def snapshot_stats(k: Kernel, step: int, reward: float) -> StepStats:
    """Aggregates of the current step."""
    speed = k.vehicle.speed
    n = int(speed.size)
    return StepStats(
        step=step,
        time=k.simulation.time,
        num_vehicles=n,
        mean_speed=float(speed.mean()) if n else math.nan,
        min_speed=float(speed.min()) if n else math.nan,
        max_speed=float(speed.max()) if n else math.nan,
        speed_std=float(np.std(speed)) if n else math.nan,
        reward=reward,
        collisions=k.simulation.step_collisions,
        teleports=k.simulation.step_teleports,
    )
