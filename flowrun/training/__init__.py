"""Training with stable-baselines3: ``train`` a config's policy, ``evaluate`` a run folder.

Importing this package needs no train extra; torch and stable-baselines3 are imported when
training or evaluation starts (:mod:`flowrun.training.deps`). The public names below are
loaded on first use (PEP 562), so that importing a light submodule such as
:mod:`flowrun.training.deps` or :mod:`flowrun.training.algorithms` does not import the
trainer, the evaluation and the kernel they run on.
"""

from __future__ import annotations

import importlib
import sys
from types import ModuleType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from flowrun.config.schedules import LinearSchedule, parse_schedule
    from flowrun.training.evaluate import EvalResult, all_human, evaluate
    from flowrun.training.trainer import TrainResult, train

#: Each public name and the module that defines it.
_PUBLIC = {
    "EvalResult": "flowrun.training.evaluate",
    "LinearSchedule": "flowrun.config.schedules",
    "TrainResult": "flowrun.training.trainer",
    "all_human": "flowrun.training.evaluate",
    "evaluate": "flowrun.training.evaluate",
    "parse_schedule": "flowrun.config.schedules",
    "train": "flowrun.training.trainer",
}

__all__ = [
    "EvalResult",
    "LinearSchedule",
    "TrainResult",
    "all_human",
    "evaluate",
    "parse_schedule",
    "train",
]


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use (and then cached here)."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_PUBLIC})


class _Package(ModuleType):
    """This package's module type: ``flowrun.training.evaluate`` stays the function.

    Importing the submodule :mod:`flowrun.training.evaluate` sets the package's attribute
    ``evaluate`` to that module; the function of the same name is kept there instead, as when
    the package imported it eagerly. The submodule itself is ``sys.modules[...]`` as always.
    """

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "evaluate" and isinstance(value, ModuleType):
            value = value.evaluate
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
