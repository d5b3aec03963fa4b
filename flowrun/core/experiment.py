"""Flow compatibility: re-exports.

Flow's ``flow.core.experiment``: ``Experiment(flow_params).run(num_runs)``.

Both of Flow's forms work: ``Experiment(flow_params).run(num_runs, rl_actions=None,
convert_to_csv=False)`` (the horizon comes from ``EnvParams``) and the tutorial's
``Experiment(env).run(num_runs, num_steps)``. See :class:`flowrun.experiment.runner.Experiment`.
"""

from flowrun.experiment.runner import Experiment

__all__ = ["Experiment"]
