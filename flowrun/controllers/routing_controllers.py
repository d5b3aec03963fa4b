"""Flow compatibility: re-exports.

Flow's ``flow.controllers.routing_controllers`` import path (flowrun's classes).
"""

from flowrun.controllers.i210_router import I210Router
from flowrun.controllers.minicity_router import MinicityRouter
from flowrun.controllers.routing import ContinuousRouter, GridRouter

__all__ = ["ContinuousRouter", "GridRouter", "I210Router", "MinicityRouter"]
