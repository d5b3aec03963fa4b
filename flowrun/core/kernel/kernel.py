"""Flow compatibility: re-exports. Flow's ``flow.core.kernel.kernel`` path.

``Kernel(simulator, sim_params)``, Flow's manual kernel lifecycle, lives in
:mod:`flowrun.kernel.flow_lifecycle`.
"""

from flowrun.kernel.flow_lifecycle import Kernel

__all__ = ["Kernel"]
