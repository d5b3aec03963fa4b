"""flowrun's shared vocabulary: the array types and the car-following inputs.

The lowest module of the package: it imports numpy only, so every layer (the kernel, the
controllers, the envs, the numpy backend, recording, replay) can use these names without
importing anything above itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

#: float64 array (positions in m, speeds in m/s, accelerations in m/s^2, ...).
FloatArray = npt.NDArray[np.float64]
#: float32 array (observations and actions handed to RL libraries).
Float32Array = npt.NDArray[np.float32]
#: int64 array (slots, lane indices, counts).
IntArray = npt.NDArray[np.int64]
#: boolean mask.
BoolArray = npt.NDArray[np.bool_]


@dataclass
class CarFollowingInputs:
    """State of a group of vehicles at one step (all arrays have one entry per vehicle).

    The kernel fills one per controller group every step; a controller turns it into one
    acceleration per vehicle. Read-only by convention (``dataclasses.replace`` makes a
    changed copy); not a frozen dataclass, whose constructor costs four times as much
    (about 18,800 against 4,500 instructions for these 11 fields), once per group and step.

    Attributes:
        speed: ego speed, m/s.
        headway: bumper-to-bumper gap to the leader, m (``inf`` when there is no leader).
        leader_speed: leader's speed, m/s (equal to ``speed`` when there is no leader).
        follower_headway: gap from the follower's front bumper to the ego's rear, m
            (``inf`` when there is no follower).
        follower_speed: follower's speed, m/s (equal to ``speed`` when there is none).
        speed_limit: speed limit of the ego's lane, m/s.
        dt: simulation step, s.
        time: simulation time, s.
        max_accel: the vehicle type's maximum acceleration (SUMO ``accel``), m/s^2, or
            ``None`` when unknown. Used by controllers that Flow caps or that fall back to
            "full throttle" without a leader, and by the ``feasible_accel`` fail-safe.
        max_decel: the vehicle type's maximum deceleration (SUMO ``decel``, positive), m/s^2,
            or ``None`` when unknown.
        length: the vehicle's length, m, or ``None`` when unknown (Flow's LAC uses it).
    """

    speed: FloatArray
    headway: FloatArray
    leader_speed: FloatArray
    follower_headway: FloatArray
    follower_speed: FloatArray
    speed_limit: FloatArray
    dt: float
    time: float = 0.0
    max_accel: FloatArray | None = None
    max_decel: FloatArray | None = None
    length: FloatArray | None = None

    @property
    def size(self) -> int:
        """Number of vehicles."""
        return int(self.speed.shape[0])

    @property
    def has_leader(self) -> BoolArray:
        """Whether each vehicle has a leader (finite headway)."""
        return np.isfinite(self.headway)
