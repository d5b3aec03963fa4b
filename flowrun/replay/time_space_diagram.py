"""Time-space diagram of a run, from its MCAP log (Flow's ``flow.visualize.time_space_diagram``).

Flow builds the diagram from an emission CSV; flowrun logs every step to MCAP, so the
functions here take the log's path and reuse :mod:`flowrun.replay`::

    from flowrun.visualize.time_space_diagram import time_space_diagram
    time_space_diagram("runs/sugiyama/<run>/run_0.mcap", "tsd.png")
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from flowrun.recording import open_log
from flowrun.replay.analysis import TimeSpace, time_space_points
from flowrun.replay.plots import plot_stride, plot_time_space
from flowrun.replay.trajectory import import_data_from_trajectory, plot_tsd, time_space_segments


def get_time_space_data(
    mcap_path: str | os.PathLike[str] | Any,
    params: Mapping[str, Any] | None = None,
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
) -> tuple[Any, ...]:
    """The diagram's points: one per vehicle per logged step.

    Given Flow's arguments instead — the DataFrame of
    :func:`~flowrun.replay.trajectory.import_data_from_trajectory` and ``flow_params`` — it
    returns Flow's ``(segs, data)`` (:func:`~flowrun.replay.trajectory.time_space_segments`).

    Args:
        mcap_path: a flowrun MCAP log.
        params: Flow's ``flow_params`` (with a DataFrame only).
        start_s, end_s: time window, s (``None``: from the start / to the end).
        vehicles: only these vehicle ids (``None``: all).

    Returns:
        ``(times, positions, speeds, ids)`` in s, m (absolute position), m/s.

    Raises:
        RecordingError: the file is missing or not a flowrun log.
    """
    if not isinstance(mcap_path, str | os.PathLike):
        return time_space_segments(mcap_path, params)
    ts = time_space_points(open_log(mcap_path), start_s=start_s, end_s=end_s, vehicles=vehicles)
    return ts.times, ts.positions, ts.speeds, [str(i) for i in ts.ids]


def time_space_diagram(
    mcap_path: str | os.PathLike[str],
    out_png: str | os.PathLike[str] | None = None,
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
) -> Path:
    """Plot position vs time coloured by speed (RL vehicles in black) and save it as PNG.

    Args:
        mcap_path: a flowrun MCAP log.
        out_png: where to write the image (default: beside the log, ``<log>_tsd.png``).
        start_s, end_s: time window, s.
        vehicles: only these vehicle ids (``None``: all).

    Returns:
        the path of the written PNG.

    Raises:
        RecordingError: the log cannot be read or the image cannot be written.
    """
    log = open_log(mcap_path)
    out = (
        Path(out_png)
        if out_png is not None
        else Path(mcap_path).with_name(Path(mcap_path).stem + "_tsd.png")
    )
    data: TimeSpace = time_space_points(
        log, start_s=start_s, end_s=end_s, vehicles=vehicles, every=plot_stride(log)
    )
    return plot_time_space(log, out, data=data)


__all__ = [
    "get_time_space_data",
    "import_data_from_trajectory",
    "plot_tsd",
    "time_space_diagram",
]
