"""Flow's ``flow.controllers.base_controller`` import path.

``BaseController`` is flowrun's :class:`~flowrun.controllers.base.AccelerationController`:
a subclass implements the vectorised ``_accel(inputs)``, not Flow's ``get_accel(env)``.
"""

from flowrun.controllers.base import AccelerationController

BaseController = AccelerationController

__all__ = ["BaseController"]
