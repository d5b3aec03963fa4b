"""Flow compatibility: re-exports. Flow's ``flow.visualize`` path.

``flowrun.visualize.time_space_diagram`` is the module (as in Flow); the plot is drawn by
:mod:`flowrun.replay.time_space_diagram` from flowrun's MCAP logs.
"""
