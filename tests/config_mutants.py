"""Seeded mutants of the shipped configs (``configs/*.yaml``) for the config fuzz tests.

A mutant is the YAML text of a shipped config changed in one way: a key dropped, a leaf value
replaced (wrong type, negative, zero, NaN, inf, huge, string, list, null, bool), an unknown
key added at some level, or the text itself broken (syntax, duplicate keys, tabs, aliases,
bytes). :func:`check_outcome` states what every mutant must give: a valid config, or one
:class:`ConfigError` naming the file, a line and (for a mutated value) the key path.
"""

from __future__ import annotations

import copy
import random
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from flowrun.config.yamlio import parse_yaml
from flowrun.errors import ConfigError

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
SHIPPED = sorted(CONFIGS.glob("*.yaml"))

Path_ = tuple[str | int, ...]

#: Replacement values of a leaf, by kind.
REPLACEMENTS: dict[str, Any] = {
    "wrong_type": {"fuzz": 1},
    "negative": None,  # computed from the leaf
    "zero": 0,
    "nan": float("nan"),
    "inf": float("inf"),
    "huge": 1e308,
    "string": "fuzz",
    "list": [1, 2],
    "null": None,
    "bool": True,
}


@dataclass(frozen=True)
class Mutant:
    """One mutated config.

    Attributes:
        kind: ``drop``, ``replace:<kind>``, ``unknown_key``, or a text kind.
        config: the shipped config it comes from (file stem).
        at: the key path it changes (``()`` for text mutants).
        text: the YAML text (``bytes`` for byte-level mutants; see :class:`DataMutant`).
    """

    kind: str
    config: str
    at: Path_
    text: str | bytes


def shipped_data(path: Path) -> dict[str, Any]:
    """A shipped config as plain data."""
    data, _ = parse_yaml(path.read_text(encoding="utf-8"), str(path))
    assert isinstance(data, dict)
    return data


def walk(data: Any, at: Path_ = ()) -> Iterator[tuple[Path_, Any]]:
    """Every ``(key path, value)`` below ``data`` (mappings and lists included)."""
    items = data.items() if isinstance(data, dict) else enumerate(data)
    for key, value in items:
        yield (*at, key), value
        if isinstance(value, dict | list):
            yield from walk(value, (*at, key))


def _get(data: Any, at: Path_) -> Any:
    for part in at:
        data = data[part]
    return data


def dump(data: Any) -> str:
    """Plain data as YAML (block style, keys in order)."""
    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
    return yaml.dump(data, Dumper=dumper, sort_keys=False, allow_unicode=True)


_DROP = object()


@dataclass(frozen=True)
class DataMutant(Mutant):
    """A mutant of the config's data, rendered to text only when read (dumping is slow).

    Attributes:
        data: the shipped config's data.
        new: the value put at ``at`` (or a marker: drop it, add an unknown key below it).
    """

    data: Any = None
    new: Any = None

    @property
    def yaml_text(self) -> str:
        """The mutated config as YAML."""
        mutant = copy.deepcopy(self.data)
        parent = _get(mutant, self.at[:-1])
        if self.new is _DROP:
            del parent[self.at[-1]]
        else:
            parent[self.at[-1]] = copy.deepcopy(self.new)
        return dump(mutant)


def data_mutants(path: Path, rng: random.Random, per_leaf: int) -> list[Mutant]:
    """Drop each key; give each leaf ``per_leaf`` replacement kinds (seeded); add an unknown
    key to every mapping (and at the top)."""
    data = shipped_data(path)
    out: list[Mutant] = []
    name = path.stem

    def add(kind: str, at: Path_, new: Any) -> None:
        out.append(DataMutant(kind, name, at, "", data, new))

    for at, value in list(walk(data)):
        add("drop", at, _DROP)
        if isinstance(value, dict):
            add("unknown_key", (*at, "fuzz_unknown_key"), 1)
        if isinstance(value, dict | list) and value:
            continue
        for kind in rng.sample(sorted(REPLACEMENTS), per_leaf):
            new = REPLACEMENTS[kind]
            if kind == "negative":
                number = isinstance(value, int | float) and not isinstance(value, bool)
                new = -abs(value) - 1 if number else -1
            if new == value and type(new) is type(value):
                continue
            add(f"replace:{kind}", at, new)
    add("unknown_key", ("fuzz_unknown_key",), 1)
    return out


def text_mutants(path: Path, rng: random.Random) -> list[Mutant]:
    """The file's own text broken: syntax, duplicate keys, tabs, aliases, bytes."""
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines(keepends=True)
    name = path.stem
    keyed = [i for i, line in enumerate(lines) if re.match(r"^\s*[A-Za-z_]+:", line)]
    out = []
    i = rng.choice(keyed)
    before, after = "".join(lines[:i]), "".join(lines[i + 1 :])
    broken = f"{before}{lines[i].rstrip()} [\n{after}"
    out.append(Mutant("syntax:unclosed_bracket", name, (), broken))
    out.append(Mutant("syntax:bad_indent", name, (), f"{before}   {lines[i]}{after}"))
    out.append(Mutant("syntax:stray_colon", name, (), text + "::: :\n"))
    top = [ln for ln in lines if re.match(r"^[a-z_]+:", ln)]
    out.append(Mutant("duplicate_key", name, (), text + rng.choice(top)))
    indented = [j for j in keyed if lines[j].startswith("  ")]
    j = rng.choice(indented)
    out.append(Mutant("tab", name, (), "".join(lines[:j]) + "\t" + lines[j].lstrip(" ")
                      + "".join(lines[j + 1:])))  # fmt: skip
    out.append(Mutant("alias_bomb", name, (), text + _bomb()))
    out.append(Mutant("alias_recursive", name, (), text + "fuzz: &a [1, *a]\n"))
    out.append(Mutant("alias_undefined", name, (), text + "fuzz: *nowhere\n"))
    out.append(Mutant("deep_nesting", name, (), text + "fuzz: " + "[" * 3000 + "]" * 3000 + "\n"))
    raw = text.encode()
    k = rng.randrange(len(raw))
    out.append(Mutant("bytes:nul", name, (), raw[:k] + b"\x00" + raw[k:]))
    out.append(Mutant("bytes:latin1", name, (), raw[:k] + b"\xe9t\xe9" + raw[k:]))
    out.append(Mutant("bytes:garbage", name, (), bytes(rng.randrange(256) for _ in range(512))))
    out.append(Mutant("bytes:truncated_utf8", name, (), raw + "é".encode()[:1]))
    return out


def _bomb(levels: int = 9) -> str:
    rows = ["fuzz_a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    for n in range(1, levels):
        refs = ", ".join([f"*a{n - 1}"] * 10)
        rows.append(f"fuzz_a{n}: &a{n} [{refs}]")
    return "\n".join(rows) + "\n"


def write(tmp: Path, mutant: Mutant, index: int) -> Path:
    """The mutant as a file in ``tmp``, named after its config (so the name is its stem)."""
    folder = tmp / f"m{index}"
    folder.mkdir()
    file = folder / f"{mutant.config}.yaml"
    if isinstance(mutant, DataMutant):
        file.write_text(mutant.yaml_text, encoding="utf-8")
    elif isinstance(mutant.text, bytes):
        file.write_bytes(mutant.text)
    else:
        file.write_text(mutant.text, encoding="utf-8")
    return file


def check_outcome(err: ConfigError, file: Path, mutant: Mutant) -> str | None:
    """What is wrong with a refusal (``None`` if it is as required)."""
    rendered = str(err)
    if "\n" in rendered or "Traceback" in rendered:
        return f"not one line: {rendered!r}"
    if not re.fullmatch(rf"{re.escape(str(file))}:\d+", err.location or ""):
        return f"location {err.location!r} is not {file}:<line>"
    if mutant.at and not err.path:
        return f"no key path in {rendered!r}"
    return None
