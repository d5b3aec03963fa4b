"""The ``train`` extra (torch, stable-baselines3, sb3-contrib) is imported lazily, here only.

``flowrun`` itself runs without it; a training command asks :func:`require` first and gets a
:class:`TrainingError` that says how to install it.
"""

from __future__ import annotations

import importlib
from types import ModuleType

#: What installs the extra from the flowrun folder (torch first: its CPU build, not a CUDA one).
INSTALL_HINT = "pip install torch==2.13.0 && pip install -e '.[train]' (in the flowrun folder)"


def import_module(name: str) -> ModuleType:
    """``importlib.import_module`` (a seam tests replace to simulate a missing extra)."""
    return importlib.import_module(name)


def require(module: str = "stable_baselines3") -> ModuleType:
    """Import one module of the train extra, or explain how to install it.

    Raises:
        TrainingError: the module (or one it needs, e.g. torch) is not installed.
    """
    from flowrun.errors import TrainingError

    try:
        return import_module(module)
    except ModuleNotFoundError as err:
        missing = err.name or module
        raise TrainingError(
            f"training needs the 'train' extra, but the module '{missing}' is not installed; "
            f"install it with: {INSTALL_HINT}"
        ) from None
