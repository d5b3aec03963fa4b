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


def removed_keywords(
    handlers: Mapping[str, Callable[[str, Any], None]],
) -> Callable[[type[T]], type[T]]:
    """Class decorator: accept keywords Flow itself removed, without storing them.

    Each handler gets ``(class name, value)`` and either warns (the value means what
    flowrun does anyway) or raises a :class:`~flowrun.errors.ConfigError` that says what
    to write instead. The keyword is then dropped, so the object is what it would be
    without it (``__dict__``, ``dataclasses.replace`` and the YAML dump are unchanged).
    """

    def decorate(cls: type[T]) -> type[T]:
        init = cls.__init__

        @functools.wraps(init)
        def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
            for key, handle in handlers.items():
                if key in kwargs:
                    handle(cls.__name__, kwargs.pop(key))
            init(self, *args, **kwargs)

        setattr(cls, "__init__", __init__)  # noqa: B010 - mypy forbids assigning a method
        return cls

    return decorate


def no_internal_links(owner: str, value: Any) -> None:
    """Flow's ``NetParams(no_internal_links=...)``, removed by Flow in 2019.

    Since then Flow always builds junction-internal links where roads meet, which is what
    ``no_internal_links=False`` asked for and what flowrun does (the ring, with no real
    junctions, has none). ``False`` is accepted with a warning; ``True`` (a network without
    junction links) is refused: neither Flow's later versions nor flowrun can build it.

    Raises:
        ConfigError: ``value`` is true.
    """
    from flowrun.errors import ConfigError

    if value:
        raise ConfigError(
            f"{owner}(no_internal_links=True) is not supported: Flow removed the option in "
            "2019 and builds junction-internal links wherever roads meet (the ring has none); "
            "remove the argument",
            path="net.no_internal_links",
        )
    warnings.warn(
        f"{owner}: 'no_internal_links' was removed by Flow in 2019; junction-internal links "
        "are always built where roads meet, as no_internal_links=False asked; remove the "
        "argument",
        DeprecationWarning,
        stacklevel=3,
    )
