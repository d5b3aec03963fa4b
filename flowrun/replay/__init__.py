"""Replay a flowrun MCAP log: summary, comparison, CSV export, plots, wave analysis."""

from flowrun.replay.analysis import (
    SpeedSeries,
    TimeSpace,
    speed_series,
    time_space_data,
    time_space_points,
    wave_drift,
)
from flowrun.replay.export import CSV_COLUMNS, to_csv
from flowrun.replay.plots import plot_speeds, plot_time_space, plot_vehicle_speeds
from flowrun.replay.summary import ReplaySummary, compare, run_label, summarize, summary_rows

__all__ = [
    "CSV_COLUMNS",
    "ReplaySummary",
    "SpeedSeries",
    "TimeSpace",
    "compare",
    "plot_speeds",
    "plot_time_space",
    "plot_vehicle_speeds",
    "run_label",
    "speed_series",
    "summarize",
    "summary_rows",
    "time_space_data",
    "time_space_points",
    "to_csv",
    "wave_drift",
]
