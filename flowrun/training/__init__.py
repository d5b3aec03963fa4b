"""Training with stable-baselines3: ``train`` a config's policy, ``evaluate`` a run folder.

Importing this package needs no train extra; torch and stable-baselines3 are imported when
training or evaluation starts (:mod:`flowrun.training.deps`).
"""

from flowrun.config.schedules import LinearSchedule, parse_schedule
from flowrun.training.evaluate import EvalResult, all_human, evaluate
from flowrun.training.trainer import TrainResult, train

__all__ = [
    "EvalResult",
    "LinearSchedule",
    "TrainResult",
    "all_human",
    "evaluate",
    "parse_schedule",
    "train",
]
