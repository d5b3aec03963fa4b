"""Copy the kernel's per-step snapshot into the log's frame types."""

from __future__ import annotations

import math
from operator import mul

import numpy as np
import numpy.typing as npt

from flowrun.kernel import Kernel
from flowrun.recording.frames import StepStats, VehicleFrame

FloatArray = npt.NDArray[np.float64]


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
    """Aggregates of the current step (see :func:`speed_stats`)."""
    sim = k.simulation
    n, mean, low, high, std = speed_stats(k.vehicle.speed)
    return StepStats(
        step, sim.time, n, mean, low, high, std, reward, sim.step_collisions, sim.step_teleports
    )


#: Up to this many vehicles, plain Python beats numpy's per-call overhead.
_SMALL = 64


def speed_stats(speed: FloatArray) -> tuple[int, float, float, float, float]:
    """Count, mean, min, max and population standard deviation of speeds (m/s).

    No vehicles: count 0 and ``nan`` elsewhere.
    """
    n = int(speed.size)
    if not n:
        return 0, math.nan, math.nan, math.nan, math.nan
    if n > _SMALL:
        mean = float(_add(speed)) / n
        dev = speed - mean
        return n, mean, float(_min(speed)), float(_max(speed)), math.sqrt(float(dev @ dev) / n)
    values = speed.tolist()
    mean = math.fsum(values) / n
    devs = [x - mean for x in values]
    return n, mean, min(values), max(values), math.sqrt(math.fsum(map(mul, devs, devs)) / n)


_add = np.add.reduce
_min = np.minimum.reduce
_max = np.maximum.reduce
