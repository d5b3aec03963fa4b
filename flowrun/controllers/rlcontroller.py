"""Flow compatibility: re-exports.

Flow's ``flow.controllers.rlcontroller`` import path (flowrun's class).
"""

from flowrun.controllers.rl import RLController

__all__ = ["RLController"]
