"""Flow compatibility: re-exports.

Flow's ``flow.core`` import paths: ``params``, ``experiment`` and ``rewards``.

Code written for Flow runs with ``flow.core`` changed to ``flowrun.core``; the objects live in
:mod:`flowrun.config.params`, :mod:`flowrun.experiment` and :mod:`flowrun.envs.rewards`.
"""
