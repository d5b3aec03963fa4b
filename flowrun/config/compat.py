"""Flow's old keyword spellings for the parameter classes (``minGap=`` for ``min_gap=``).

Flow still accepts its pre-0.4 camelCase keywords (``SumoCarFollowingParams(minGap=...)``,
``SumoLaneChangeParams(lcStrategic=...)``) with a deprecation warning; so does flowrun, with
the same result as the snake_case keyword. An unknown keyword is a ``TypeError`` that says
which names exist (with a did-you-mean), as Python's own message would not.
"""

from __future__ import annotations

import dataclasses
import functools
import warnings
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

from flowrun.suggest import did_you_mean

T = TypeVar("T")


def flow_keywords(aliases: Mapping[str, str]) -> Callable[[type[T]], type[T]]:
    """Class decorator: accept ``aliases`` (old keyword -> field name) in the constructor.

    The class keeps the mapping as ``FLOW_KEYWORDS`` (the YAML loader names the field to
    write instead). ``dataclasses.replace`` and pickling keep working: the constructor still
    takes every field by its own name.
    """

    def decorate(cls: type[T]) -> type[T]:
        init = cls.__init__
        fields = [f.name for f in dataclasses.fields(cls) if f.init]  # type: ignore[arg-type]
        known = [*fields, *aliases]

        @functools.wraps(init)
        def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
            for key in list(kwargs):
                if key in aliases:
                    new = aliases[key]
                    if new in kwargs:
                        raise TypeError(
                            f"{cls.__name__}: '{key}' and '{new}' are the same setting; "
                            "give only one"
                        )
                    warnings.warn(
                        f"{cls.__name__}: '{key}' is Flow's deprecated spelling; use '{new}'",
                        DeprecationWarning,
                        stacklevel=2,
                    )
                    kwargs[new] = kwargs.pop(key)
                elif key not in fields:
                    raise TypeError(
                        f"{cls.__name__}() got an unexpected keyword argument '{key}'"
                        f"{did_you_mean(key, known)}; it takes: {', '.join(fields)}"
                    )
            init(self, *args, **kwargs)

        setattr(cls, "__init__", __init__)  # noqa: B010 - mypy forbids assigning a method
        setattr(cls, "FLOW_KEYWORDS", dict(aliases))  # noqa: B010
        return cls

    return decorate
