"""CSV export with Flow's emission columns, so existing Flow analysis scripts keep working."""

from __future__ import annotations

import csv
import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from flowrun.errors import RecordingError
from flowrun.recording import McapLog
from flowrun.recording.atomic import PARTIAL_SUFFIX, new_file

CSV_COLUMNS = (
    "time",
    "id",
    "type",
    "x",
    "y",
    "speed",
    "headway",
    "leader_id",
    "follower_id",
    "leader_rel_speed",
    "target_accel",
    "realized_accel",
    "road_grade",
    "edge_id",
    "lane_number",
    "distance",
    "relative_position",
)


def _cells(values: np.ndarray) -> list[object]:
    """Floats as exact reprs; ``nan`` as an empty cell, ``inf`` as ``inf``."""
    nan = np.isnan(values)
    if not nan.any():
        return values.tolist()
    out = values.astype(object)
    out[nan] = ""
    return out.tolist()


def to_csv(
    log: McapLog,
    path: str | os.PathLike[str],
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
    overwrite: bool = True,
) -> int:
    """Write one row per vehicle per logged step; returns the number of rows.

    ``follower_id`` is the vehicle whose leader this one is ("" if none);
    ``leader_rel_speed`` is the leader's speed minus this vehicle's speed (empty without a
    leader); ``target_accel`` is the commanded acceleration (empty where SUMO drove the car);
    ``distance`` is the odometer and ``relative_position`` the position along the lane (m);
    ``road_grade`` is 0.

    The rows go to a ``.partial`` file renamed to ``path`` when complete, so an interrupted
    export never leaves a half CSV under ``path``.

    Args:
        log: an opened log.
        path: the CSV file.
        start_s: first simulation time to export, s.
        end_s: last simulation time to export, s.
        vehicles: only these vehicle ids.
        overwrite: replace an existing ``path`` (``False``: refuse, as the CLI does).

    Raises:
        RecordingError: ``path`` exists and ``overwrite`` is false, or it cannot be written.
    """
    out = Path(path)
    if overwrite and out.is_file():  # the library's old contract: replace it (atomically)
        tmp = out.with_name(f".{out.name}.{os.getpid()}{PARTIAL_SUFFIX}")
        try:
            rows = _write_csv(log, tmp, start_s, end_s, vehicles)
            os.replace(tmp, out)
        except OSError as err:
            raise RecordingError(f"cannot write CSV {out}: {err.strerror or err}") from None
        finally:
            tmp.unlink(missing_ok=True)
        return rows
    with new_file(out, "the CSV export") as tmp:
        return _write_csv(log, tmp, start_s, end_s, vehicles)


def _write_csv(
    log: McapLog,
    out: Path,
    start_s: float | None,
    end_s: float | None,
    vehicles: Iterable[str] | None,
) -> int:
    rows = 0
    with open(out, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(CSV_COLUMNS)
        for frame in log.frames(start_s, end_s, vehicles):
            n = len(frame.ids)
            if n == 0:
                continue
            index = {vid: i for i, vid in enumerate(frame.ids)}
            follower = [""] * n
            lead_speed = np.full(n, np.nan)
            for i, leader in enumerate(frame.leader):
                j = index.get(leader)
                if j is not None:
                    follower[j] = frame.ids[i]
                    lead_speed[i] = frame.speed[j]
            writer.writerows(
                zip(
                    [frame.time] * n,
                    frame.ids,
                    frame.types,
                    _cells(frame.x),
                    _cells(frame.y),
                    _cells(frame.speed),
                    _cells(frame.headway),
                    frame.leader,
                    follower,
                    _cells(lead_speed - frame.speed),
                    _cells(frame.accel_cmd),
                    _cells(frame.accel_real),
                    [0] * n,
                    frame.edges,
                    frame.lanes.tolist(),
                    _cells(frame.odometer),
                    _cells(frame.lane_pos),
                    strict=True,
                )
            )
            rows += n
    return rows
