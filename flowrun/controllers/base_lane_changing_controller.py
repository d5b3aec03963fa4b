"""Flow compatibility: re-exports.

Flow's ``flow.controllers.base_lane_changing_controller`` import path.
"""

from flowrun.controllers.lane_change import LaneChangeController

BaseLaneChangeController = LaneChangeController

__all__ = ["BaseLaneChangeController"]
