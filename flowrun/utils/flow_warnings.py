"""Flow compatibility: re-exports. Flow's ``flow.utils.flow_warnings`` path.

``deprecated_attribute`` and ``deprecated`` live in :mod:`flowrun.deprecation`,
``deprecation_warning`` in :mod:`flowrun.errors`.
"""

from flowrun.deprecation import deprecated, deprecated_attribute
from flowrun.errors import deprecation_warning

__all__ = ["deprecated", "deprecated_attribute", "deprecation_warning"]
