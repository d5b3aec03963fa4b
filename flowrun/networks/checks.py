"""Declared checks of network parameter values (``ADDITIONAL_NET_PARAMS`` entries).

A network lists each parameter's kind once (``positive``, ``count``, ...); :func:`check_values`
validates them all and names the offending key in the :class:`ConfigError`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from flowrun.errors import ConfigError


def _is_number(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float)


def _is_int(value: Any) -> bool:
    return not isinstance(value, bool) and (
        isinstance(value, int) or (isinstance(value, float) and value.is_integer())
    )


#: kind -> (test, what the message says was expected)
KINDS: dict[str, tuple[Callable[[Any], bool], str]] = {
    "positive": (lambda v: _is_number(v) and v > 0, "a number > 0"),
    "non_negative": (lambda v: _is_number(v) and v >= 0, "a number >= 0"),
    "count": (lambda v: _is_int(v) and v >= 1, "an integer >= 1"),
    "resolution": (lambda v: _is_int(v) and v >= 2, "an integer >= 2"),
    "flag": (lambda v: isinstance(v, bool), "true or false"),
}


def check_values(params: dict[str, Any], kinds: dict[str, str]) -> None:
    """Raise :class:`ConfigError` (``path`` = the key) for the first value of the wrong kind.

    Args:
        params: resolved parameters (defaults overlaid with the user's).
        kinds: parameter name -> a key of :data:`KINDS`.
    """
    for key, kind in kinds.items():
        test, expected = KINDS[kind]
        if not test(params[key]):
            raise ConfigError(f"expected {expected}, got {params[key]!r}", path=key)
