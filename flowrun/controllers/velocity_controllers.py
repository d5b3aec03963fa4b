"""Flow compatibility: re-exports.

Flow's ``flow.controllers.velocity_controllers`` import path (flowrun's classes).
"""

from flowrun.controllers.nonlocal_follower_stopper import NonLocalFollowerStopper
from flowrun.controllers.velocity import FollowerStopper, PISaturation

__all__ = ["FollowerStopper", "NonLocalFollowerStopper", "PISaturation"]
