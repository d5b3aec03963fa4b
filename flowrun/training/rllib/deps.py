"""The ``rllib`` extra (Ray RLlib, torch) is imported here, lazily, with a one-line error."""

from __future__ import annotations

import importlib
from types import ModuleType

from flowrun.errors import TrainingError

#: The command that installs what ``train.backend: rllib`` needs (torch first: CPU build).
INSTALL_HINT = "pip install torch==2.13.0 && pip install -e '.[rllib]' (in the flowrun folder)"


def require_ray(purpose: str = "train.backend: rllib", rllib: bool = True) -> ModuleType:
    """Import Ray (with RLlib and torch, RLlib's framework here, unless ``rllib`` is false), or
    say how to install them.

    Args:
        purpose: what needs Ray, for the error message.
        rllib: whether RLlib and torch are needed too (a sweep on Ray needs Ray core only).

    Returns:
        the ``ray`` module.

    Raises:
        TrainingError: Ray, RLlib or torch is not installed.
    """
    try:
        for name in ("torch", "ray.rllib") if rllib else ("ray",):
            importlib.import_module(name)
    except ModuleNotFoundError as err:
        missing = err.name or "ray"
        raise TrainingError(
            f"{purpose} needs the 'rllib' extra, but the module '{missing}' is not "
            f"installed; install it with: {INSTALL_HINT}"
        ) from None
    return importlib.import_module("ray")
