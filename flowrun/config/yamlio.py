"""YAML text <-> plain Python data, remembering the line of every key.

PyYAML's ``safe_load`` forgets where a value came from and silently keeps the last of two
equal keys. Here the file is *composed* into PyYAML's node tree and walked by hand: scalars
are built by PyYAML's own safe constructor (so ``.inf``, ``null``, ``yes`` mean what YAML says),
every mapping key and list item records its line, and a repeated key is an error.

Three YAML 1.1 surprises are changed to what YAML 1.2 (and a reader) expects: ``1:30`` is the
text ``"1:30"``, not the sexagesimal number 90; ``1e-3`` is a number, not a string; and
``2024-05-01`` is text, not a date.
Hostile input is refused cheaply, as one :class:`ConfigError`: a document nested deeper than
:data:`MAX_DEPTH` levels, or one whose aliases expand to more than :data:`MAX_VALUES` values
(a "billion laughs" bomb), and characters YAML forbids (a NUL byte: a binary file).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import yaml

from flowrun.errors import ConfigError

PathPart = str | int
KeyPath = tuple[PathPart, ...]

OVERRIDE_LOCATION = "--set"

#: Deepest nesting of mappings and lists a config may have (flowrun's own need a handful).
MAX_DEPTH = 64
#: Most values (scalars, mappings, lists; an alias counts each time it is used) in a document.
MAX_VALUES = 100_000

_TAG_INT = "tag:yaml.org,2002:int"
_TAG_FLOAT = "tag:yaml.org,2002:float"
_TAG_STR = "tag:yaml.org,2002:str"
_TAG_TIMESTAMP = "tag:yaml.org,2002:timestamp"  # no setting is a date: ``2024-05-01`` is text
# YAML 1.2 floats with an exponent but no dot or no exponent sign (``1e-3``, ``1.5e3``),
# which YAML 1.1 reads as strings.
_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")


# libyaml's parser when PyYAML was built with it (about ten times faster), else PyYAML's own.
_SafeLoader: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class ConfigLoader(_SafeLoader):  # type: ignore[valid-type,misc]
    """PyYAML's safe loader with YAML 1.2 numbers: no sexagesimal ``1:30``, ``1e5`` a float."""

    def resolve(self, kind: Any, value: Any, implicit: Any) -> Any:
        """The tag of a scalar: as PyYAML's, except for the two numbers above."""
        tag = super().resolve(kind, value, implicit)
        if kind is yaml.ScalarNode and implicit[0]:
            if (tag in (_TAG_INT, _TAG_FLOAT) and ":" in value) or tag == _TAG_TIMESTAMP:
                return _TAG_STR
            if tag == _TAG_STR and _EXPONENT_FLOAT.match(value):
                return _TAG_FLOAT
        return tag


def load_scalar(text: str) -> Any:
    """One YAML value (an override's ``value``), read as a config file's values are.

    Raises:
        yaml.YAMLError: the text is not YAML.
    """
    loader = ConfigLoader(text)
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


def format_path(path: Iterable[PathPart]) -> str:
    """Render a key path the way users write it: ``vehicles[0].acceleration_controller.v0``."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


@dataclass
class Locations:
    """Where each key path of a parsed document stands (``file:line``).

    Attributes:
        source: the file name (or ``<dict>``) used when no line is known.
        where: ``file:line`` (or ``--set``) per key path.
    """

    source: str
    where: dict[KeyPath, str] = field(default_factory=dict)

    def of(self, path: Iterable[PathPart]) -> str:
        """Location of ``path``, or of its nearest ancestor that has one."""
        key = tuple(path)
        while key:
            if key in self.where:
                return self.where[key]
            key = key[:-1]
        return self.where.get((), self.source)

    def error(self, message: str, path: Iterable[PathPart]) -> ConfigError:
        """A :class:`ConfigError` located at ``path``."""
        key = tuple(path)
        return ConfigError(message, format_path(key), self.of(key))

    def replace(self, path: KeyPath, location: str) -> None:
        """Forget the locations under ``path`` (its value was replaced) and set ``path``'s."""
        n = len(path)
        for key in [k for k in self.where if k[:n] == path and len(k) > n]:
            del self.where[key]
        self.where[path] = location


class _Walker:
    """Turns a composed node tree into plain data and fills a :class:`Locations`."""

    def __init__(self, loader: yaml.SafeLoader, locations: Locations) -> None:
        self.loader = loader
        self.locations = locations
        self.open: set[int] = set()  # nodes being walked, to refuse a recursive alias

    def line_of(self, node: yaml.Node) -> str:
        return f"{self.locations.source}:{node.start_mark.line + 1}"

    def check_size(self, node: yaml.Node) -> None:
        """Refuse a document nested too deeply or expanding to too many values, before any
        value is built (each distinct node is sized once, so a bomb costs nothing)."""
        sizes: dict[int, int] = {}

        def size(node: yaml.Node, path: KeyPath) -> int:
            if id(node) in sizes:
                return sizes[id(node)]
            if len(path) > MAX_DEPTH:
                raise ConfigError(
                    f"nested more than {MAX_DEPTH} levels deep; a config has a few levels",
                    format_path(path[:3]) + "...",
                    self.line_of(node),
                )
            sizes[id(node)] = 1  # a recursive alias stops here; value() refuses it
            total = 1
            if isinstance(node, yaml.MappingNode):
                for key_node, value_node in node.value:
                    total += 1 + size(value_node, (*path, str(key_node.value)[:40]))
            elif isinstance(node, yaml.SequenceNode):
                for i, item in enumerate(node.value):
                    total += size(item, (*path, i))
            if total > MAX_VALUES:
                raise ConfigError(
                    f"expands to more than {MAX_VALUES} values (aliases used inside aliases?); "
                    "a config is a few hundred values: write it out without nested aliases",
                    format_path(path),
                    self.line_of(node),
                )
            sizes[id(node)] = total
            return total

        size(node, ())

    def value(self, node: yaml.Node, path: KeyPath) -> Any:
        if isinstance(node, yaml.ScalarNode):
            return self.loader.construct_object(node, deep=True)
        if id(node) in self.open:
            raise ConfigError(
                "an alias refers to a value that contains it", format_path(path), self.line_of(node)
            )
        self.open.add(id(node))
        try:
            if isinstance(node, yaml.MappingNode):
                return self.mapping(node, path)
            items = []
            for i, item in enumerate(node.value):
                self.locations.where[(*path, i)] = self.line_of(item)
                items.append(self.value(item, (*path, i)))
            return items
        finally:
            self.open.discard(id(node))

    def mapping(self, node: yaml.MappingNode, path: KeyPath) -> dict[Any, Any]:
        seen: dict[Any, yaml.Node] = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue
            key = self.key(key_node, path)
            if key in seen:
                first = seen[key].start_mark.line + 1
                raise ConfigError(
                    f"duplicate key '{key}' (first given on line {first}); keep only one",
                    format_path((*path, key)),
                    self.line_of(key_node),
                )
            seen[key] = key_node
        self.loader.flatten_mapping(node)  # resolve ``<<: *anchor`` merges; own keys win
        out: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            key = self.key(key_node, path)
            self.locations.where[(*path, key)] = self.line_of(key_node)
            out[key] = self.value(value_node, (*path, key))
        return out

    def key(self, node: yaml.Node, path: KeyPath) -> Any:
        if not isinstance(node, yaml.ScalarNode):
            raise ConfigError(
                "a mapping key must be a plain name, not a list or mapping",
                format_path(path),
                self.line_of(node),
            )
        return self.loader.construct_object(node)


def parse_yaml(text: str, source: str) -> tuple[Any, Locations]:
    """Parse one YAML document into plain data and the location of every key.

    Args:
        text: the YAML text.
        source: file name used in locations (``configs/ring.yaml``).

    Returns:
        The data (``None`` for an empty document) and its :class:`Locations`.

    Raises:
        ConfigError: invalid YAML (at the line PyYAML reports) or a key given twice.
    """
    locations = Locations(source)
    loader: ConfigLoader | None = None
    try:
        loader = ConfigLoader(text)  # the reader checks every character here
        node = loader.get_single_node()
        if node is None:
            return None, locations
        locations.where[()] = f"{source}:{node.start_mark.line + 1}"
        walker = _Walker(loader, locations)
        walker.check_size(node)
        return walker.value(node, ()), locations
    except yaml.MarkedYAMLError as err:
        mark = err.problem_mark or err.context_mark
        where = f"{source}:{mark.line + 1}" if mark is not None else source
        what = err.problem or err.context or "unreadable"
        if err.problem and err.context:
            what = f"{err.problem} ({err.context})"
        if "nesting depth" in what:  # PyYAML >= 6.0.3 stops deep documents itself
            what = f"nested too deeply to read (more than {MAX_DEPTH} levels is never a config)"
        raise ConfigError(f"invalid YAML: {what}", "", where) from None
    except yaml.reader.ReaderError as err:  # a NUL or another character YAML forbids
        line = text.count("\n", 0, max(err.position, 0)) + 1
        code = int(err.character) if isinstance(err.character, int) else ord(err.character)
        what = "a NUL byte" if code == 0 else f"the character #x{code:04x}"
        raise ConfigError(
            f"contains {what}, which YAML does not allow: is this a binary file? "
            "A config is a YAML text file",
            "",
            f"{source}:{line}",
        ) from None
    except yaml.YAMLError as err:
        raise ConfigError(f"invalid YAML: {err}", "", source) from None
    except RecursionError:  # PyYAML's composer recurses once per nesting level
        raise ConfigError(
            f"nested too deeply to read (more than {MAX_DEPTH} levels is never a config)",
            "",
            source,
        ) from None
    finally:
        if loader is not None:
            loader.dispose()


class _Dumper(yaml.SafeDumper):
    """Safe dumper that indents list items under their key (``vehicles:\\n  - id: ...``)."""

    def increase_indent(self, flow: bool = False, indentless: bool = False) -> None:
        super().increase_indent(flow, False)


def _plain(value: Any) -> Any:
    """Tuples become lists (YAML has no tuples); everything else is left as is."""
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def dump_yaml(data: Mapping[str, Any]) -> str:
    """Plain data as block-style YAML, keys in the order given."""
    return yaml.dump(
        _plain(data), Dumper=_Dumper, sort_keys=False, default_flow_style=False, width=100
    )
