"""Flow compatibility: re-exports. Flow's ``flow.utils.flow_warnings`` path.

``deprecation_warning`` lives in :mod:`flowrun.errors`.
"""

from flowrun.errors import deprecation_warning

__all__ = ["deprecation_warning"]
