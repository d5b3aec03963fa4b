"""Flow's ``flow.visualize`` import path: plots from flowrun's MCAP logs.

``flowrun.visualize.time_space_diagram`` is the module (as in Flow); its function
:func:`~flowrun.visualize.time_space_diagram.time_space_diagram` draws the plot.
"""
