"""Flow's time-space diagram from a trajectory CSV (Flow's emission file), as Flow draws it.

Flow's three steps, with Flow's signatures::

    df = import_data_from_trajectory("ring-0_emission.csv", flow_params)
    segs, df = get_time_space_data(df, flow_params)
    plot_tsd(ax, df, segs, args)   # args: min_speed, max_speed, start

The CSV is the one ``Experiment.run(..., convert_to_csv=True)`` writes (or Flow's own); a
file without a ``distance`` column gets it from the network's edge starts. These functions
need pandas (``pip install pandas``); :func:`flowrun.replay.time_space_diagram.time_space_diagram`
draws the same plot straight from a run's MCAP log without it.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from flowrun.errors import RecordingError

#: Flow's colour map: red at standstill, yellow at 60 % of the range, green at the top.
_CMAP_POINTS = (
    (0.0, (0.0, 0.0, 0.0)),
    (0.2, (1.0, 0.0, 0.0)),
    (0.6, (1.0, 1.0, 0.0)),
    (1.0, (0.0, 1.0, 0.0)),
)
_SEGMENT_COLUMNS = ["time_step", "distance", "next_time", "next_pos"]


def _pandas() -> Any:
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - pandas is installed with the dev tools
        raise RecordingError(
            "Flow's trajectory functions need pandas: pip install pandas "
            "(or plot from the run's MCAP log with flowrun.replay.time_space_diagram)"
        ) from e
    return pandas


def _edge_starts(params: Mapping[str, Any]) -> dict[str, float]:
    """The network's edge starts (m), from ``params["network"]`` (a class) and ``params["net"]``."""
    network, net = params.get("network"), params.get("net")
    if not isinstance(network, type) or net is None:
        raise RecordingError(
            "the trajectory file has no 'distance' column: give flow_params (with 'network', "
            "a network class, and 'net', its NetParams) to compute it from the edge starts"
        )
    from flowrun.config.params import VehicleParams

    built = network("time_space", VehicleParams(), net)
    return {e: float(x) for e, x in (*built.edge_starts, *built.internal_edge_starts)}


def import_data_from_trajectory(
    fp: str | os.PathLike[str], params: Mapping[str, Any] | None = None
) -> Any:
    """Read a trajectory (emission) CSV into a DataFrame ready for the diagram (Flow's name).

    Columns are renamed as Flow does (``time`` → ``time_step``, ``lane_number`` → ``lane_id``);
    ``distance`` is added when missing (edge start + ``relative_position``); ``next_pos`` and
    ``next_time`` hold each vehicle's next sample, and each vehicle's last sample is dropped.

    Args:
        fp: the CSV file.
        params: Flow's ``flow_params`` (``network`` and ``net`` are read, and only when the
            file has no ``distance`` column).

    Returns:
        a ``pandas.DataFrame``, one row per vehicle and step that has a next step.

    Raises:
        RecordingError: the file is missing, or has no ``distance`` and no network is given.
    """
    pd = _pandas()
    if not os.path.isfile(fp):
        raise RecordingError(f"{fp}: no such trajectory file (a CSV written with convert_to_csv)")
    df = pd.read_csv(fp).rename(columns={"time": "time_step", "lane_number": "lane_id"})
    if "distance" not in df.columns:
        starts = _edge_starts(params or {})
        distance = df["relative_position"] + df["edge_id"].map(starts).fillna(0.0)
        if _network_name(params) == "FigureEightNetwork":
            distance = _fold_figure_eight(distance.to_numpy(dtype=float), starts, params or {})
        df["distance"] = distance
    df[["next_pos", "next_time"]] = df.groupby("id")[["distance", "time_step"]].shift(-1)
    return df[df["next_time"].notna()]


def time_space_segments(data: Any, params: Mapping[str, Any] | None = None) -> tuple[Any, Any]:
    """Flow's ``get_time_space_data(data, params)``: the line segments of the diagram.

    Returns:
        ``(segs, data)``: ``segs`` an ``(n, 2, 2)`` array of ``[[t0, x0], [t1, x1]]``, one per
        row of ``data``; for Flow's I210 sub-network a dict of such arrays keyed by lane.
    """
    name = _network_name(params)
    if name == "I210SubNetwork":
        return {lane: _segments(df) for lane, df in data.groupby("lane_id")}, data
    if name == "MergeNetwork":  # Flow's merge diagram: the on-ramp's edges only
        data = data[data["edge_id"].isin(_MERGE_EDGES)]
    return _segments(data), data


#: the edges Flow's merge diagram keeps
_MERGE_EDGES = ("inflow_merge", "bottom", ":bottom_0")


def _network_name(params: Mapping[str, Any] | None) -> str | None:
    return getattr((params or {}).get("network"), "__name__", None)


def _fold_figure_eight(x: np.ndarray, starts: Mapping[str, float], params: Mapping[str, Any]
                       ) -> np.ndarray:  # fmt: skip
    """Flow's figure-eight layout of the diagram: positions (m along the network) folded at
    the intersection, so cars approaching it from one side run down the plot from the top
    and those from the other side up from the bottom.

    With ``c0``/``c1`` the middle of the intersection on the first/second pass (the start of
    ``:center_1``/``:center_0`` plus the ring radius) and ``L`` Flow's length of the figure
    eight (``6 * r * pi / 2 + 4 * r + 2 * junction + 10 * 0.28``, junction ``2.9 + 3.3 *
    lanes``): ``x - c1`` between them, ``c0 + L - x`` past ``c1``, and before ``c0`` (once
    moved up by ``L``) ``c0 - x``, as Flow's.
    """
    extra = params["net"].additional_params
    radius, lanes = float(extra["radius_ring"]), float(extra["lanes"])
    length = 6 * radius * np.pi / 2 + 4 * radius + 2 * (2.9 + 3.3 * lanes) + 10 * 0.28
    c0, c1 = starts[":center_1"] + radius, starts[":center_0"] + radius
    out = x.copy()
    out[x < c0] += length
    middle = (x > c0) & (x < c1)
    out[middle] -= c1
    past = out > c1  # Flow's order: the ones moved up by L included
    out[past] = c0 + length - out[past]
    return out


def _segments(df: Any) -> np.ndarray:
    return np.asarray(df[_SEGMENT_COLUMNS].to_numpy(dtype=float)).reshape((len(df), 2, 2))


def _arg(args: Any, name: str, default: float) -> float:
    value = args.get(name, default) if isinstance(args, Mapping) else getattr(args, name, default)
    return float(value)


def plot_tsd(
    ax: Any,
    df: Any,
    segs: Any,
    args: Any,
    lane: int | None = None,
    ghost_edges: Any = None,
    ghost_bounds: tuple[float, float] | None = None,
) -> Any:
    """Draw the segments on ``ax``, coloured by speed, with Flow's title, labels and colour bar.

    Args:
        ax: a matplotlib ``Axes``.
        df: the DataFrame of :func:`import_data_from_trajectory` (axis bounds, speeds).
        segs: the segments of :func:`time_space_segments` (one per row of ``df``).
        args: an ``argparse.Namespace`` or dict with ``min_speed``, ``max_speed`` (colour
            range, m/s; default 0 and 8) and ``start`` (s; the time before it is greyed).
        lane: a lane number for the title.
        ghost_edges: edges greyed out (their distance range).
        ghost_bounds: ``(low, high)`` distances outside which the plot is greyed.

    Returns:
        the ``LineCollection`` drawn.
    """
    from matplotlib.collections import LineCollection, PatchCollection
    from matplotlib.colors import LinearSegmentedColormap, Normalize
    from matplotlib.patches import Rectangle

    norm = Normalize(_arg(args, "min_speed", 0.0), _arg(args, "max_speed", 8.0))
    cmap = LinearSegmentedColormap.from_list("flow_tsd", list(_CMAP_POINTS))
    t0, t1 = float(df["time_step"].min()), float(df["time_step"].max())
    y0, y1 = float(df["distance"].min()), float(df["distance"].max())
    ax.set_xlim(t0 - 0.025 * (t1 - t0), t1 + 0.025 * (t1 - t0))
    ax.set_ylim(y0 - 0.025 * (y1 - y0), y1 + 0.025 * (y1 - y0))
    lines = LineCollection(segs, cmap=cmap, norm=norm, linewidth=1)
    lines.set_array(np.asarray(df["speed"], dtype=float))
    ax.add_collection(lines)
    start = _arg(args, "start", 0.0)
    low, high = y0, y1
    if ghost_edges:
        kept = df[~df["edge_id"].isin(ghost_edges)]["distance"]
        low, high = float(kept.min()), float(kept.max())
    elif ghost_bounds:
        low, high = ghost_bounds
    rects = [Rectangle((t0, low), start - t0, high - low)]
    if ghost_edges or ghost_bounds:
        rects += [Rectangle((t0, y0), t1 - t0, low - y0), Rectangle((t0, high), t1 - t0, y1 - high)]
    grey = PatchCollection(rects, facecolor="grey", alpha=0.5, edgecolor=None, zorder=20)
    ax.add_collection(grey)
    title = "Time-Space Diagram" + (f": Lane {lane}" if lane else "")
    ax.set_title(title, fontsize=25)
    ax.set_ylabel("Position (m)", fontsize=20)
    ax.set_xlabel("Time (s)", fontsize=20)
    ax.tick_params(labelsize=18)
    bar = ax.figure.colorbar(lines, ax=ax)
    bar.set_label("Velocity (m/s)", fontsize=20)
    bar.ax.tick_params(labelsize=18)
    return lines


__all__ = ["import_data_from_trajectory", "plot_tsd", "time_space_segments"]
