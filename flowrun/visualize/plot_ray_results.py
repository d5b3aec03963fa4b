"""Flow compatibility: re-exports. Flow's ``flow.visualize.plot_ray_results`` path.

The functions live in :mod:`flowrun.replay.progress`.
"""

from flowrun.replay.progress import create_parser, plot_progress, read_progress

__all__ = ["create_parser", "plot_progress", "read_progress"]
