"""``flowrun train`` and ``flowrun eval`` (placeholder until the training layer lands)."""

from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    """Add the training commands to the app."""
