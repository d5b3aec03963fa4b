"""Non-RL experiments: run an environment for N runs, measure, record, report."""

from flowrun.experiment.metrics import RunMetrics, summarize_run
from flowrun.experiment.runner import Experiment

__all__ = ["Experiment", "RunMetrics", "summarize_run"]
