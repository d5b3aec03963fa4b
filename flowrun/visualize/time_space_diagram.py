"""Flow compatibility: re-exports. Flow's ``flow.visualize.time_space_diagram`` path.

The functions live in :mod:`flowrun.replay.time_space_diagram`; ``get_flow_params`` (which
Flow's module imports and its users call through it) in :mod:`flowrun.envs.flow_json`.
"""

from flowrun.envs.flow_json import get_flow_params
from flowrun.replay.time_space_diagram import (
    get_time_space_data,
    import_data_from_trajectory,
    plot_tsd,
    time_space_diagram,
)

__all__ = [
    "get_flow_params",
    "get_time_space_data",
    "import_data_from_trajectory",
    "plot_tsd",
    "time_space_diagram",
]
