"""Controller parameters declared once: name, default, unit, meaning and bounds.

A built-in controller is a dataclass whose fields are its constructor's arguments in Flow's
order, so ``IDMController("human_0", 25)`` and ``IDMController(v0=25)`` work as in Flow.
Each field is made by :func:`param` (a number with bounds and a unit) or :func:`option`
(anything else, with its own check); the field's :class:`Param` is the one declaration that
validation (:func:`check_params`, run by the controller's ``__post_init__``), the
did-you-mean of unknown names and ``flowrun list controllers`` (:func:`parameters`) read.

A refused value raises :class:`ParameterValueError` naming the class, the parameter, what was
expected and what was given (``IDMController: v0 must be a finite number > 0, got -1``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import Any

#: The key of a field's :class:`Param` in ``dataclasses.field(metadata=...)``.
PARAM_KEY = "flowrun.param"

#: A non-number check: ``(class name, parameter name, value) -> stored value``.
Converter = Callable[[str, str, Any], Any]


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
    high: float | None = None,
    strict: bool = False,
    allow_inf: bool = False,
    what: str = "",
) -> float:
    """Return ``value`` as a float after checking it is a real number within bounds.

    Args:
        owner: class name, for the message.
        name: parameter name, for the message.
        value: the value given.
        low: lower bound (``None``: unbounded).
        high: upper bound (``None``: unbounded).
        strict: whether a value equal to a bound is refused.
        allow_inf: whether ``+inf`` is accepted.
        what: what the number means, put before the bounds in the message
            (``"a negative deceleration"``).
    """
    expected = f"{owner}: {name} must be {_expected(low, high, strict, what)}"
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ParameterValueError(f"{expected}, got {value!r}", name)
    x = float(value)
    if math.isnan(x) or (math.isinf(x) and not (allow_inf and x > 0)):
        raise ParameterValueError(f"{expected}, got {value!r}", name)
    if low is not None and (x < low or (strict and x == low)):
        raise ParameterValueError(f"{expected}, got {value!r}", name)
    if high is not None and (x > high or (strict and x == high)):
        raise ParameterValueError(f"{expected}, got {value!r}", name)
    return x


def _expected(low: float | None, high: float | None, strict: bool, what: str) -> str:
    bounds = [
        f"{sign}{'' if strict else '='} {bound:g}"
        for sign, bound in ((">", low), ("<", high))
        if bound is not None
    ]
    text = "a finite number" + "".join(f" {b}" for b in bounds[:1])
    text += "".join(f" and {b}" for b in bounds[1:])
    return f"{what} ({text})" if what else text


@dataclass(frozen=True)
class Param:
    """One constructor parameter of a controller.

    Attributes:
        name: the argument's name (Flow's).
        default: its default value.
        unit: its unit (``m/s``, ``s``; empty for a pure number or a non-number).
        doc: what it means, in a few words.
        low: lower bound, or the name of the parameter that is the lower bound
            (``h_go > h_st``); ``None``: unbounded.
        high: upper bound; ``None``: unbounded.
        strict: whether a value equal to a bound is refused.
        allow_inf: whether ``+inf`` is accepted.
        what: the meaning named in the error message (``"a negative deceleration"``).
        convert: for a non-number, its check; ``None``: a number checked by the bounds.
    """

    name: str
    default: Any
    unit: str
    doc: str
    low: float | str | None = None
    high: float | None = None
    strict: bool = False
    allow_inf: bool = False
    what: str = ""
    convert: Converter | None = None

    @property
    def bounds(self) -> str:
        """The bounds as text (``> 0``, ``>= 0 and <= 1``, ``> h_st``; empty when none)."""
        eq = "" if self.strict else "="
        return " and ".join(
            f"{sign}{eq} {bound if isinstance(bound, str) else format(bound, 'g')}"
            for sign, bound in ((">", self.low), ("<", self.high))
            if bound is not None
        )

    def check(self, owner: str, value: Any, obj: object) -> Any:
        """``value`` as stored, after its check (``obj`` gives a bound named by another
        parameter).

        Raises:
            ParameterValueError: the value is refused.
        """
        if self.convert is not None:
            return self.convert(owner, self.name, value)
        low = getattr(obj, self.low) if isinstance(self.low, str) else self.low
        return number(
            owner, self.name, value, low=low, high=self.high, strict=self.strict,
            allow_inf=self.allow_inf, what=self.what,
        )  # fmt: skip


def param(
    default: float,
    unit: str,
    doc: str,
    *,
    low: float | str | None = None,
    high: float | None = None,
    strict: bool = False,
    allow_inf: bool = False,
    what: str = "",
) -> Any:
    """A dataclass field for a number parameter (see :class:`Param` for the arguments)."""
    spec = Param("", default, unit, doc, low, high, strict, allow_inf, what)
    return field(default=default, metadata={PARAM_KEY: spec})


def option(default: Any, doc: str, convert: Converter, unit: str = "") -> Any:
    """A dataclass field for a non-number parameter, checked by ``convert``."""
    spec = Param("", default, unit, doc, convert=convert)
    return field(default=default, metadata={PARAM_KEY: spec})


def declared(spec: Param, **changes: Any) -> Any:
    """A dataclass field for a parameter declared ahead (the ones every controller shares),
    with ``changes`` to its :class:`Param` (``default="safe_velocity"``)."""
    spec = replace(spec, **changes)
    return field(default=spec.default, metadata={PARAM_KEY: spec})


def parameters(cls: type, base: tuple[Param, ...] = ()) -> tuple[Param, ...]:
    """The declared parameters of a controller class, in constructor order.

    A dataclass controller gives its fields' :class:`Param` (named after the field); any
    other class gives ``base`` (the parameters its base class's constructor takes).
    """
    if not is_dataclass(cls):
        return base
    return tuple(
        replace(f.metadata[PARAM_KEY], name=f.name, default=f.default)
        for f in fields(cls)
        if PARAM_KEY in f.metadata
    )


def check_params(obj: object, base: tuple[Param, ...] = ()) -> None:
    """Check every declared parameter of ``obj`` in order and store its checked value.

    Raises:
        ParameterValueError: the first refused value.
    """
    owner = type(obj).__name__
    for spec in parameters(type(obj), base):
        setattr(obj, spec.name, spec.check(owner, getattr(obj, spec.name), obj))


def flag(owner: str, name: str, value: Any) -> bool:
    """A true/false parameter (a YAML ``true``/``false``)."""
    if not isinstance(value, bool):
        raise ParameterValueError(f"{owner}: {name} must be true or false, got {value!r}", name)
    return value


def anything(owner: str, name: str, value: Any) -> Any:
    """A parameter kept as given (Flow's objects, such as ``car_following_params``)."""
    return value
