"""Parameter checks shared by the controller constructors (they raise ``ValueError``)."""

from __future__ import annotations

import math


class ParameterValueError(ValueError):
    """A constructor parameter has a bad value; ``param`` names it."""

    def __init__(self, message: str, param: str) -> None:
        super().__init__(message)
        self.param = param


def number(
    owner: str,
    name: str,
    value: object,
    *,
    low: float | None = None,
    strict: bool = False,
    allow_inf: bool = False,
) -> float:
    """Return ``value`` as a float after checking it is a real number within bounds.

    Args:
        owner: class name, for the message.
        name: parameter name, for the message.
        value: the value given.
        low: lower bound (``None``: unbounded).
        strict: whether ``value == low`` is refused.
        allow_inf: whether ``+inf`` is accepted.
    """
    bound = ""
    if low is not None:
        bound = f" {'>' if strict else '>='} {low:g}"
    expected = f"{owner}: {name} must be a finite number{bound}"
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ParameterValueError(f"{expected}, got {value!r}", name)
    x = float(value)
    if math.isnan(x) or (math.isinf(x) and not (allow_inf and x > 0)):
        raise ParameterValueError(f"{expected}, got {value!r}", name)
    if low is not None and (x < low or (strict and x == low)):
        raise ParameterValueError(f"{expected}, got {value!r}", name)
    return x
