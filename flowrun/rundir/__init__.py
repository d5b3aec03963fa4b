"""Run folders: where every command that does work puts its results.

- :mod:`~flowrun.rundir.folders`: ``runs/<config-name>/<timestamp>-<seed>/`` (never
  overwritten), the resolved config, command line and versions written into it, the metadata
  its MCAP logs carry, and ``tracked_run`` (how the run ended);
- :mod:`~flowrun.rundir.status`: ``status.json`` (the one module that writes it) and reading it
  back against the processes alive now;
- :mod:`~flowrun.rundir.train_state`: a train run's lock, ``metrics.json`` status and stop
  requests;
- :mod:`~flowrun.rundir.lock`: the folder lock; :mod:`~flowrun.rundir.safeio`: atomic JSON
  writes and readable OS errors.

Used by the experiment runner, training and the CLI; it imports only config and errors.
"""
