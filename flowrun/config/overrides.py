"""``--set a.b.c=value`` overrides applied to the plain config data before it is checked.

The value is a YAML scalar (or flow collection) read as the config file's values are
(:func:`~flowrun.config.yamlio.load_scalar`: ``1:30`` stays text), never with ``eval``.
An override may create a key that does not exist yet; the schema check that follows rejects an
unknown one with a did-you-mean, located at ``--set``.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

import yaml

from flowrun.config.yamlio import (
    OVERRIDE_LOCATION,
    KeyPath,
    Locations,
    format_path,
    load_scalar,
)
from flowrun.errors import ConfigError

_PART = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


def parse_key(key: str) -> KeyPath:
    """``vehicles[0].count`` or ``vehicles.0.count`` -> ``("vehicles", 0, "count")``."""
    parts: list[str | int] = []
    for dotted in key.split("."):
        if not dotted:
            raise ConfigError(f"empty name in override key '{key}'", key, OVERRIDE_LOCATION)
        pos = 0
        while pos < len(dotted):
            match = _PART.match(dotted, pos)
            if match is None:
                raise ConfigError(
                    f"cannot read override key '{key}'; write it like vehicles[0].count",
                    key,
                    OVERRIDE_LOCATION,
                )
            name, index = match.groups()
            if index is not None:
                parts.append(int(index))
            else:
                parts.append(int(name) if name.isdigit() else name)
            pos = match.end()
    return tuple(parts)


def parse_override(text: str) -> tuple[KeyPath, Any]:
    """Split ``a.b=value`` into a key path and the YAML value."""
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ConfigError(
            f"an override must look like key.path=value, got '{text}'", "", OVERRIDE_LOCATION
        )
    path = parse_key(key)
    try:
        value = load_scalar(raw)
    except yaml.YAMLError as err:
        problem = getattr(err, "problem", None) or getattr(err, "context", None) or "invalid"
        raise ConfigError(
            f"cannot read the value {raw!r} as YAML ({problem}); quote it or fix the brackets",
            format_path(path),
            OVERRIDE_LOCATION,
        ) from None
    return path, value


def apply_overrides(
    data: dict[str, Any], overrides: Sequence[str], locations: Locations
) -> dict[str, Any]:
    """Apply each ``key=value`` to ``data`` in place (later ones win) and return it."""
    for text in overrides:
        path, value = parse_override(text)
        _set(data, path, value, locations)
    return data


def _set(data: dict[str, Any], path: KeyPath, value: Any, locations: Locations) -> None:
    node: Any = data
    for i, part in enumerate(path[:-1]):
        node = _child(node, part, path[: i + 1], path[i + 1], locations)
    last = path[-1]
    if isinstance(node, list):
        _check_index(node, last, path)
        node[int(last)] = value
    else:
        node[str(last)] = value
    locations.replace(path, OVERRIDE_LOCATION)


def _child(node: Any, part: str | int, at: KeyPath, next_part: str | int, loc: Locations) -> Any:
    """The container at ``at`` (created if missing), ready to descend into."""
    if isinstance(node, list):
        _check_index(node, part, at)
        parent: Any = node
        key: str | int = int(part)
    else:
        parent, key = node, str(part)
        if node.get(key) is None:
            node[key] = [] if isinstance(next_part, int) else {}
            loc.replace(at, OVERRIDE_LOCATION)
    child = parent[key]
    if isinstance(child, str) and str(key).endswith("_controller"):
        child = parent[key] = {"type": child}  # ``IDM`` -> ``{type: IDM}`` to set a parameter
    if not isinstance(child, dict | list):
        raise ConfigError(
            f"'{format_path(at)}' is a value ({child!r}), not a section; cannot set keys in it",
            format_path(at),
            OVERRIDE_LOCATION,
        )
    return child


def _check_index(items: list[Any], part: str | int, at: KeyPath) -> None:
    if not isinstance(part, int):
        raise ConfigError(
            f"'{format_path(at[:-1])}' is a list; index it with a number, e.g. [0]",
            format_path(at),
            OVERRIDE_LOCATION,
        )
    if part >= len(items):
        raise ConfigError(
            f"index {part} is out of range: '{format_path(at[:-1])}' has {len(items)} item(s)",
            format_path(at),
            OVERRIDE_LOCATION,
        )
