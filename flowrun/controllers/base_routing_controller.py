"""Flow compatibility: re-exports.

Flow's ``flow.controllers.base_routing_controller`` import path.
"""

from flowrun.controllers.routing import Router

BaseRouter = Router

__all__ = ["BaseRouter"]
