"""The ``rllib`` extra (Ray RLlib, torch) is imported here, lazily, with a one-line error."""

from __future__ import annotations

import importlib
from types import ModuleType

from flowrun.errors import TrainingError

#: The command that installs what ``train.backend: rllib`` needs (torch first: CPU build).
INSTALL_HINT = "pip install torch==2.13.0 && pip install 'flowrun[rllib]'"


def require_ray() -> ModuleType:
    """Import Ray with RLlib (and torch, RLlib's framework here), or say how to install them.

    Returns:
        the ``ray`` module.

    Raises:
        TrainingError: Ray, RLlib or torch is not installed.
    """
    try:
        importlib.import_module("torch")
        importlib.import_module("ray.rllib")
    except ModuleNotFoundError as err:
        missing = err.name or "ray"
        raise TrainingError(
            f"train.backend: rllib needs the 'rllib' extra, but the module '{missing}' is not "
            f"installed; install it with: {INSTALL_HINT}"
        ) from None
    return importlib.import_module("ray")
