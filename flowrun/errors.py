"""One error hierarchy for everything a user can get wrong or the simulator can refuse.

Every message says what was expected, what was found, and how to fix it. The CLI turns a
:class:`FlowrunError` into one line on stderr and exit code 1; anything else is a bug.
"""

from __future__ import annotations

import warnings


class FlowrunError(Exception):
    """Base class of all errors flowrun reports to users."""


class ConfigError(FlowrunError):
    """A configuration file or object is invalid.

    Args:
        message: what is wrong and how to fix it.
        path: the key path, e.g. ``vehicles[0].acceleration_controller.type``.
        location: ``file:line`` where the offending value stands, when known.
    """

    def __init__(self, message: str, path: str = "", location: str = "") -> None:
        self.message = message
        self.path = path
        self.location = location
        super().__init__(self.render())

    def render(self) -> str:
        """The one-line message shown to users."""
        where = self.location
        if self.path:
            where = f"{where}: {self.path}" if where else self.path
        return f"{where}: {self.message}" if where else self.message


class MissingParameterError(ConfigError, KeyError):
    """A parameter a class requires is not given, e.g. a key of an environment's
    ``ADDITIONAL_ENV_PARAMS`` missing from ``EnvParams.additional_params``. Also a
    ``KeyError``, which is what Flow raises for it, so Flow code catching that keeps working.
    """

    __str__ = Exception.__str__  # the message as written, not KeyError's quoted repr


class CountMismatchError(ConfigError, AssertionError):
    """Counts that must agree do not, e.g. ``InitialConfig.edges_distribution``'s per-edge
    counts and the number of vehicles. Also an ``AssertionError``, which is what Flow raises
    for it, so Flow code catching that keeps working."""


class BadValueError(ConfigError, ValueError):
    """A parameter has a value its class refuses, e.g. an unknown controller ``fail_safe``.
    Also a ``ValueError``, which is what Flow raises for it, so Flow code catching that keeps
    working."""


class UnknownNameError(ConfigError, KeyError):
    """A name that is not there, e.g. a column a CSV does not have. Also a ``KeyError``, which
    is what Flow raises for it."""

    __str__ = Exception.__str__  # the message as written, not KeyError's quoted repr


class FatalFlowError(FlowrunError):
    """An error after which the simulation cannot continue (Flow's ``FatalFlowError``, also
    importable from ``flowrun.utils.exceptions``).

    Args:
        msg: what went wrong.
    """

    def __init__(self, msg: str) -> None:
        self.message = msg
        super().__init__(msg)


class SimulationError(FatalFlowError):
    """SUMO refused something or failed (netconvert output, start failure, lost vehicles).

    A :class:`FatalFlowError`, as Flow raises for the same failures (e.g. not all vehicles
    could be inserted at the start).
    """


class RecordingError(FlowrunError):
    """An MCAP log cannot be written or read."""


class TrainingError(FlowrunError):
    """Training or evaluation cannot proceed (missing extra, bad run directory, ...)."""


def deprecation_warning(obj: object, dep_from: str, dep_to: str) -> None:
    """Warn that an attribute of ``obj`` was renamed (Flow's message, as a ``UserWarning``).

    Args:
        obj: the object whose attribute was used under its old name.
        dep_from: the old attribute name.
        dep_to: the name to use instead.
    """
    warnings.warn(
        f"The attribute {dep_from} in {type(obj).__name__} is deprecated, use {dep_to} instead.",
        UserWarning,
        stacklevel=2,
    )
