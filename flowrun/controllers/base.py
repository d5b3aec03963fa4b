"""Controller contract: pure, vectorised formulas over arrays of vehicle state.

A controller object drives one *group* of vehicles (one ``VehicleParams.add`` call). Every
step the kernel hands it a :class:`CarFollowingInputs` with one entry per vehicle of the group
(always in the same order) and gets back one acceleration per vehicle, in m/s^2. Nothing here
knows about SUMO or the environment, so every formula is testable with plain numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class CarFollowingInputs:
    """State of a group of vehicles at one step (all arrays have one entry per vehicle).

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
    """

    speed: FloatArray
    headway: FloatArray
    leader_speed: FloatArray
    follower_headway: FloatArray
    follower_speed: FloatArray
    speed_limit: FloatArray
    dt: float
    time: float = 0.0

    @property
    def size(self) -> int:
        """Number of vehicles."""
        return int(self.speed.shape[0])


class AccelerationController:
    """Base of all acceleration controllers.

    Subclasses implement :meth:`_accel` (the formula). :meth:`get_accel` adds Flow's Gaussian
    acceleration noise, ``sqrt(dt) * N(0, noise)``, drawn from the generator it is given.

    Attributes:
        registered_name: the name configs use (``type: IDM``).
        commands_sumo: ``False`` for controllers that leave the car to SUMO's own model.
        is_rl: ``True`` for the RL agent's placeholder.
    """

    registered_name: ClassVar[str] = ""
    aliases: ClassVar[tuple[str, ...]] = ()
    commands_sumo: ClassVar[bool] = True
    is_rl: ClassVar[bool] = False

    def __init__(self, noise: float = 0.0) -> None:
        if noise < 0 or not math.isfinite(noise):
            raise ValueError(f"noise must be a finite number >= 0, got {noise}")
        self.noise = float(noise)

    def reset(self, num_vehicles: int) -> None:
        """Forget any per-vehicle memory; called at every environment reset."""

    def get_accel(self, inputs: CarFollowingInputs, rng: np.random.Generator) -> FloatArray:
        """Accelerations (m/s^2) for every vehicle of the group, noise included."""
        accel = self._accel(inputs)
        if self.noise > 0:
            accel = accel + math.sqrt(inputs.dt) * rng.normal(0.0, self.noise, inputs.size)
        return accel

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        raise NotImplementedError
