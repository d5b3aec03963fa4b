"""Flow compatibility: re-exports.

Flow's ``flow.utils.exceptions`` import path.
"""

from __future__ import annotations

from flowrun.errors import FatalFlowError

__all__ = ["FatalFlowError"]
