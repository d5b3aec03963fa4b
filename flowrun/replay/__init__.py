"""Replay a flowrun MCAP log: summary, comparison, CSV export, plots, wave analysis, and
traffic along a route (time-space diagram, speed, density, outflow) on open networks."""

from flowrun.replay.analysis import (
    SpeedSeries,
    TimeSpace,
    speed_series,
    time_space_data,
    time_space_points,
    wave_drift,
)
from flowrun.replay.export import CSV_COLUMNS, to_csv
from flowrun.replay.plots import plot_speeds, plot_time_space, plot_traffic, plot_vehicle_speeds
from flowrun.replay.route import NetTopology, RouteLayout, layout_for, parse_route, route_layout
from flowrun.replay.summary import ReplaySummary, compare, run_label, summarize, summary_rows
from flowrun.replay.traffic import Outflow, TrafficSeries, outflow, traffic_series

__all__ = [
    "CSV_COLUMNS",
    "NetTopology",
    "Outflow",
    "ReplaySummary",
    "RouteLayout",
    "SpeedSeries",
    "TimeSpace",
    "TrafficSeries",
    "compare",
    "layout_for",
    "outflow",
    "parse_route",
    "plot_speeds",
    "plot_time_space",
    "plot_traffic",
    "plot_vehicle_speeds",
    "route_layout",
    "run_label",
    "speed_series",
    "summarize",
    "summary_rows",
    "time_space_data",
    "time_space_points",
    "to_csv",
    "traffic_series",
    "wave_drift",
]
