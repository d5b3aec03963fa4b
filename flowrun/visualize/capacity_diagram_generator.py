"""Flow compatibility: re-exports. Flow's ``flow.visualize.capacity_diagram_generator`` path.

The functions live in :mod:`flowrun.replay.capacity`.
"""

from flowrun.replay.capacity import create_parser, get_capacity_data, import_data_from_csv

__all__ = ["create_parser", "get_capacity_data", "import_data_from_csv"]
