"""Flow's ``flow.controllers.routing_controllers`` import path (flowrun's classes)."""

from flowrun.controllers.routing import ContinuousRouter, GridRouter

__all__ = ["ContinuousRouter", "GridRouter"]
