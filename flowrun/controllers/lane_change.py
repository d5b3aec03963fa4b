"""Lane-change controllers.

A lane-change controller returns, per vehicle, a direction: ``+1`` left, ``-1`` right, ``0``
keep the lane, or ``None`` for the whole group when SUMO's own lane-change model decides
(``commands_sumo = False``).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from flowrun.controllers.base import takes_env_only
from flowrun.types import IntArray


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
    #: ``True`` for a Flow-style subclass implementing ``get_lane_change_action(env)``: the
    #: environment makes one per vehicle and applies its answer every step
    per_vehicle: ClassVar[bool] = False

    def __init__(self, veh_id: str | None = None, lane_change_params: Any = None) -> None:
        self.veh_id = veh_id
        self.lane_change_params = lane_change_params

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        own = cls.get_lane_change_action is not LaneChangeController.get_lane_change_action
        cls.per_vehicle = own and takes_env_only(cls.get_lane_change_action)

    def get_lane_change(self, num_vehicles: int) -> IntArray | None:
        """Directions (``+1`` left, ``-1`` right, ``0`` stay), or ``None``: SUMO decides."""
        raise NotImplementedError

    def get_lane_change_action(self, env: Any) -> int | None:
        """Flow's per-vehicle hook: this vehicle's direction (``-1``, ``0``, ``1``) or
        ``None``. A Flow-style subclass implements it; the built-ins answer from
        :meth:`get_lane_change`."""
        directions = self.get_lane_change(1)
        return None if directions is None else int(directions[0])

    def get_action(self, env: Any) -> int | None:
        """Flow's ``get_action(env)``: :meth:`get_lane_change_action`."""
        return self.get_lane_change_action(env)


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
