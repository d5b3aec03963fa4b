"""Flow compatibility: re-exports.

Flow's ``flow.controllers.routing_controllers`` import path (flowrun's classes).
"""

from flowrun.controllers.minicity_router import MinicityRouter
from flowrun.controllers.routing import ContinuousRouter, GridRouter

__all__ = ["ContinuousRouter", "GridRouter", "MinicityRouter"]
