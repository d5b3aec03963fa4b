"""Non-RL experiments: run an environment for N runs, measure, record, report."""

from flowrun.experiment.metrics import RunAccumulator, RunMetrics
from flowrun.experiment.runner import Experiment

__all__ = ["Experiment", "RunAccumulator", "RunMetrics"]
