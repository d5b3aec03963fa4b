"""Non-RL experiments: run an environment for N runs, measure, record, report.

The names below load on first use, so that importing a light submodule (``rundir``, which
every CLI command uses) does not import the environments.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from flowrun.experiment.metrics import RunAccumulator, RunMetrics
    from flowrun.experiment.runner import Experiment

__all__ = ["Experiment", "RunAccumulator", "RunMetrics"]

_WHERE = {
    "Experiment": "flowrun.experiment.runner",
    "RunAccumulator": "flowrun.experiment.metrics",
    "RunMetrics": "flowrun.experiment.metrics",
}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(import_module(_WHERE[name]), name)
    raise AttributeError(f"module 'flowrun.experiment' has no attribute {name!r}")
