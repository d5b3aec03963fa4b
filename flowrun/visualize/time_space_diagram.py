"""Flow compatibility: re-exports. Flow's ``flow.visualize.time_space_diagram`` path.

The functions live in :mod:`flowrun.replay.time_space_diagram`.
"""

from flowrun.replay.time_space_diagram import (
    get_time_space_data,
    import_data_from_trajectory,
    plot_tsd,
    time_space_diagram,
)

__all__ = ["get_time_space_data", "import_data_from_trajectory", "plot_tsd", "time_space_diagram"]
