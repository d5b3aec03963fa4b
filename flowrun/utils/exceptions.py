"""Flow's ``flow.utils.exceptions`` import path."""

from __future__ import annotations

from flowrun.errors import FlowrunError


class FatalFlowError(FlowrunError):
    """An error after which the simulation cannot continue (Flow's ``FatalFlowError``).

    Part of flowrun's error hierarchy, so the CLI reports it as one line.

    Args:
        msg: what went wrong.
    """

    def __init__(self, msg: str) -> None:
        self.message = msg
        super().__init__(msg)


__all__ = ["FatalFlowError"]
