"""Flow compatibility: re-exports.

Flow's ``flow.controllers.base_controller`` import path.

``BaseController`` is flowrun's :class:`~flowrun.controllers.base.AccelerationController`.
A subclass either implements Flow's per-vehicle ``get_accel(self, env)`` (one object per
vehicle, driven as Flow drives it; see :mod:`flowrun.controllers.per_vehicle`) or flowrun's
vectorised ``_accel(inputs)`` (one object per vehicle group, the fast path).
"""

from flowrun.controllers.base import AccelerationController

BaseController = AccelerationController

__all__ = ["BaseController"]
