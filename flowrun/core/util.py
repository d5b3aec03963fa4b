"""Flow's ``flow.core.util``: ``emission_to_csv`` (SUMO emission XML -> Flow's CSV) and
``ensure_dir``.

flowrun itself logs runs to MCAP and exports Flow's emission CSV from there
(``Experiment.run(convert_to_csv=True)``, ``flowrun replay --csv``); these helpers serve Flow
code and SUMO emission files written outside flowrun.
"""

from __future__ import annotations

import csv
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

#: Flow's CSV columns, in Flow's order, and the SUMO ``<vehicle>`` attribute each comes from.
_COLUMNS: tuple[tuple[str, str, bool], ...] = (
    ("CO", "CO", True),
    ("y", "y", True),
    ("CO2", "CO2", True),
    ("electricity", "electricity", True),
    ("type", "type", False),
    ("id", "id", False),
    ("eclass", "eclass", False),
    ("waiting", "waiting", True),
    ("NOx", "NOx", True),
    ("fuel", "fuel", True),
    ("HC", "HC", True),
    ("x", "x", True),
    ("route", "route", False),
    ("relative_position", "pos", True),
    ("noise", "noise", True),
    ("angle", "angle", True),
    ("PMx", "PMx", True),
    ("speed", "speed", True),
)

#: The header Flow's ``emission_to_csv`` writes.
EMISSION_CSV_COLUMNS: tuple[str, ...] = (
    "time",
    *(c for c, _, _ in _COLUMNS),
    "edge_id",
    "lane_number",
)


def ensure_dir(path: str) -> str:
    """Create ``path`` (and its parents) if missing; return it (Flow's ``ensure_dir``)."""
    os.makedirs(path, exist_ok=True)
    return path


def _rows(emission_path: str | Path) -> list[dict[str, Any]]:
    rows: list[dict[str, Any]] = []
    time = 0.0
    try:
        for event, elem in ET.iterparse(str(emission_path), events=("start", "end")):
            if event == "start" and elem.tag == "timestep":
                time = float(elem.attrib["time"])
            elif event == "end" and elem.tag == "vehicle":
                row = _row(time, elem.attrib)
                if row is not None:
                    rows.append(row)
                elem.clear()
    except ET.ParseError:
        pass  # a file cut short (SUMO stopped mid-write): keep what was read, as Flow does
    return rows


def _row(time: float, attrib: dict[str, str]) -> dict[str, Any] | None:
    row: dict[str, Any] = {"time": time}
    try:
        for column, attr, numeric in _COLUMNS:
            row[column] = float(attrib[attr]) if numeric else attrib[attr]
        edge, _, lane = attrib["lane"].rpartition("_")
    except KeyError:
        return None  # Flow skips vehicles whose record lacks a field
    row["edge_id"] = edge
    row["lane_number"] = lane
    return row


def emission_to_csv(emission_path: str, output_path: str | None = None) -> str:
    """Convert a SUMO emission XML file to Flow's emission CSV.

    One row per vehicle and time step, with the columns of :data:`EMISSION_CSV_COLUMNS`
    (SUMO's ``pos`` is ``relative_position``; the lane id is split into ``edge_id`` and
    ``lane_number``). Rows are sorted by vehicle id (stable, so by time within a vehicle);
    vehicle records missing a field are skipped; a file cut short is read up to the cut.

    Args:
        emission_path: the ``*-emission.xml`` file.
        output_path: where to write; default: ``emission_path`` with its last three
            characters (``xml``) replaced by ``csv``, as Flow.

    Returns:
        the path written.
    """
    rows = sorted(_rows(emission_path), key=lambda r: r["id"])
    if output_path is None:
        output_path = emission_path[:-3] + "csv"
    with open(output_path, "w", newline="") as f:
        writer = csv.DictWriter(f, EMISSION_CSV_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    return output_path
