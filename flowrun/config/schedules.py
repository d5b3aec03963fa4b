"""Learning-rate and clip-range schedules written as data, never ``eval``.

A value in ``train.hyperparams`` may be a number (constant) or a one-key mapping:

- ``{linear: 3e-4}``: decays linearly from 3e-4 to 0 over training;
- ``{linear: [3e-4, 1e-5]}``: linearly from 3e-4 to 1e-5;
- ``{constant: 3e-4}``: the same as ``3e-4``.

SB3 calls a schedule with ``progress_remaining``, which goes from 1 (start) to 0 (end).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from flowrun.errors import ConfigError
from flowrun.suggest import unknown_name

# Hyper-parameters SB3 accepts as a schedule (a float or a function of progress_remaining).
SCHEDULE_PARAMS = ("learning_rate", "clip_range", "clip_range_vf", "delta_std")
KINDS = ("linear", "constant")


@dataclass(frozen=True)
class LinearSchedule:
    """``start`` at the beginning of training to ``end`` at its end (picklable)."""

    start: float
    end: float = 0.0

    def __call__(self, progress_remaining: float) -> float:
        """The value when ``progress_remaining`` (1 -> 0) of training is left."""
        return self.end + (self.start - self.end) * progress_remaining


def _number(value: Any, path: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(f"expected a number, got {value!r}", path)
    return float(value)


def parse_schedule(value: Any, path: str) -> float | Callable[[float], float]:
    """A number, ``{linear: x}``, ``{linear: [start, end]}`` or ``{constant: x}`` -> SB3 value.

    Raises:
        ConfigError: anything else, at ``path``.
    """
    if not isinstance(value, Mapping):
        return _number(value, path)
    if len(value) != 1:
        raise ConfigError(
            f"a schedule is one of {{linear: x}}, {{linear: [start, end]}}, {{constant: x}}; "
            f"got {dict(value)!r}",
            path,
        )
    ((kind, arg),) = value.items()
    if kind not in KINDS:
        raise ConfigError(unknown_name("schedule", str(kind), KINDS, sort=False), path)
    if kind == "constant":
        return _number(arg, f"{path}.constant")
    if isinstance(arg, list):
        if len(arg) != 2:
            raise ConfigError(f"expected [start, end], got {arg!r}", f"{path}.linear")
        return LinearSchedule(_number(arg[0], f"{path}.linear"), _number(arg[1], f"{path}.linear"))
    return LinearSchedule(_number(arg, f"{path}.linear"))
