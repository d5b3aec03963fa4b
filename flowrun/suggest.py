"""Did-you-mean suggestions for misspelt names."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


def did_you_mean(name: str, choices: Iterable[str]) -> str:
    """Return ``" (did you mean 'x'?)"`` for the closest choice, or ``""`` if none is close."""
    options = list(choices)
    lowered = {c.lower(): c for c in options}
    close = difflib.get_close_matches(name.lower(), list(lowered), n=1, cutoff=0.6)
    if close:
        return f" (did you mean '{lowered[close[0]]}'?)"
    return ""


def unknown_name(kind: str, name: str, choices: Iterable[str]) -> str:
    """Message for an unknown name of some kind, listing the valid ones."""
    options = sorted(choices)
    return f"unknown {kind} '{name}'{did_you_mean(name, options)}; expected one of: " + ", ".join(
        options
    )
