"""Training with Ray RLlib (``train.backend: rllib``): PPO on RLlib's current API stack.

``train_rllib`` and ``evaluate_rllib`` take the same arguments as the stable-baselines3 path's
:func:`flowrun.training.train` and :func:`flowrun.training.evaluate` and write the same run
folder. Importing this package needs no Ray: Ray is imported when training starts, and a
missing ``rllib`` extra is one :class:`~flowrun.errors.TrainingError` naming the install
command (:func:`flowrun.training.rllib.deps.require_ray`).
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from flowrun.training.rllib.deps import INSTALL_HINT, require_ray

__all__ = ["INSTALL_HINT", "evaluate_rllib", "is_rllib_run", "require_ray", "train_rllib"]


def is_rllib_run(run_dir: Path) -> bool:
    """Whether a train run folder holds RLlib checkpoints (``flowrun eval`` picks
    :func:`evaluate_rllib` for it) rather than stable-baselines3 models. Needs no Ray."""
    names = ("final_checkpoint", "best_checkpoint")
    if any((run_dir / name / "learner_group").is_dir() for name in names):
        return True
    return any((run_dir / "checkpoints").glob("iter_*/learner_group"))


_LAZY = {
    "train_rllib": "flowrun.training.rllib.train",
    "evaluate_rllib": "flowrun.training.rllib.evaluate",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)
