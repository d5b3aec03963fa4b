"""Flow compatibility: re-exports.

Flow's ``flow.controllers.lane_change_controllers`` import path (flowrun's classes).
"""

from flowrun.controllers.lane_change import SimLaneChangeController, StaticLaneChanger

__all__ = ["SimLaneChangeController", "StaticLaneChanger"]
