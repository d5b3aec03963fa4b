"""Lane-change controllers.

A lane-change controller returns, per vehicle, a direction: ``+1`` left, ``-1`` right, ``0``
keep the lane, or ``None`` for the whole group when SUMO's own lane-change model decides
(``commands_sumo = False``).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

IntArray = npt.NDArray[np.int_]


class LaneChangeController:
    """Base of lane-change controllers (one instance per vehicle group).

    Args:
        veh_id: Flow's vehicle id (Flow passes it first; informative here).
        lane_change_params: the vehicle type's ``SumoLaneChangeParams`` (kept as given).

    Attributes:
        registered_name: the name configs use (``type: StaticLaneChanger``).
        commands_sumo: ``False`` when SUMO's lane-change model decides.
    """

    registered_name: ClassVar[str] = ""
    aliases: ClassVar[tuple[str, ...]] = ()
    commands_sumo: ClassVar[bool] = True

    def __init__(self, veh_id: str | None = None, lane_change_params: Any = None) -> None:
        self.veh_id = veh_id
        self.lane_change_params = lane_change_params

    def get_lane_change(self, num_vehicles: int) -> IntArray | None:
        """Directions (``+1`` left, ``-1`` right, ``0`` stay), or ``None``: SUMO decides."""
        raise NotImplementedError


class SimLaneChangeController(LaneChangeController):
    """SUMO's lane-change model (``SumoLaneChangeParams``) decides."""

    registered_name = "SimLaneChangeController"
    aliases = ("SimLaneChange",)
    commands_sumo = False

    def get_lane_change(self, num_vehicles: int) -> IntArray | None:
        """Always ``None``: no command."""
        return None


class StaticLaneChanger(LaneChangeController):
    """Never change lane: every direction is 0 (the kernel should also switch SUMO's own
    lane changing off for the group)."""

    registered_name = "StaticLaneChanger"

    def get_lane_change(self, num_vehicles: int) -> IntArray | None:
        """Zeros: stay in the current lane."""
        return np.zeros(num_vehicles, dtype=np.int_)
