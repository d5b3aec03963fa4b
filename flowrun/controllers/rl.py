"""Acceleration "controllers" that give no command: the RL agent's and SUMO's own.

Both return ``nan`` for every vehicle; the kernel must check the class attributes
(``is_rl``, ``commands_sumo``) rather than the values to decide who drives.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from flowrun.controllers.base import (
    CAR_FOLLOWING_PARAMS,
    VEH_ID,
    AccelerationController,
)
from flowrun.controllers.params import declared
from flowrun.types import CarFollowingInputs, FloatArray


@dataclass(eq=False)
class RLController(AccelerationController):
    """Placeholder for vehicles the RL agent drives (``is_rl = True``).

    The environment's ``_apply_rl_actions`` supplies their accelerations; :meth:`get_accel`
    returns ``nan`` (no command from the controller layer).
    """

    registered_name = "RLController"
    aliases = ("RL",)
    is_rl = True

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        return np.full(inputs.size, np.nan)


@dataclass(eq=False)
class SimCarFollowingController(AccelerationController):
    """Leave the vehicle to SUMO's own car-following model (``commands_sumo = False``).

    :meth:`get_accel` returns ``nan``. Noise and fail-safes are SUMO's business here (set
    them through ``SumoCarFollowingParams``), as in Flow.
    """

    registered_name = "SimCarFollowingController"
    aliases = ("SimCarFollowing", "SUMO")
    commands_sumo = False

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        return np.full(inputs.size, np.nan)
