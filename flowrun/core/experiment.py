"""Flow's ``flow.core.experiment``: ``Experiment(env).run(num_runs, num_steps)``."""

from flowrun.experiment.runner import Experiment

__all__ = ["Experiment"]
