"""``Experiment.run(convert_to_csv=True)``: per-step vehicle states as CSV, as Flow wrote them.

Flow's simulation kernel kept every vehicle's state at every step and wrote it, at the end of
run ``i``, to ``<emission_path>/<network name>-<i>_emission.csv`` (:data:`FLOW_EMISSION_COLUMNS`).
flowrun logs each run to MCAP (in a fresh folder under ``emission_path``) and writes Flow's
file from that log (:func:`flow_emission_csv`).

Flow's ``flow.core.util`` helpers are here too: :func:`emission_to_csv` (a SUMO emission XML
file, written outside flowrun, to Flow's CSV) and :func:`ensure_dir`.
"""

from __future__ import annotations

import csv
import logging
import math
import os
import xml.etree.ElementTree as ET
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from flowrun.config.dump import dump_config
from flowrun.config.model import ExperimentConfig
from flowrun.envs.base import Env
from flowrun.envs.frames import network_metadata
from flowrun.errors import ConfigError
from flowrun.flow_values import FLOW_ERROR, FLOW_NO_GAP
from flowrun.recording.writer import McapRecorder
from flowrun.rundir.folders import unique_dir

log = logging.getLogger(__name__)

#: Flow's emission CSV columns, in Flow's order (``TraCISimulation.save_emission``).
FLOW_EMISSION_COLUMNS = (
    "time",
    "id",
    "x",
    "y",
    "speed",
    "headway",
    "leader_id",
    "target_accel_with_noise_with_failsafe",
    "target_accel_no_noise_no_failsafe",
    "target_accel_with_noise_no_failsafe",
    "target_accel_no_noise_with_failsafe",
    "realized_accel",
    "road_grade",
    "edge_id",
    "lane_number",
    "distance",
    "relative_position",
    "follower_id",
    "leader_rel_speed",
)


def emission_dir(env: Env, name: str) -> Path:
    """A fresh folder under ``sim_params.emission_path`` for this experiment's logs and CSVs.

    Raises:
        ConfigError: ``emission_path`` is not set (as Flow, which then has nowhere to write).
    """
    base = env.sim_params.emission_path
    if base is None:
        raise ConfigError(
            "convert_to_csv=True needs a folder to write to: set "
            "SumoParams(emission_path='./data') (YAML: sim.emission_path)",
            path="sim.emission_path",
        )
    stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
    return unique_dir(Path(base) / f"{name}-{stamp}")


def run_recorder(
    folder: Path, env: Env, run: int, cfg: ExperimentConfig | None = None
) -> McapRecorder:
    """The MCAP log of run ``run`` in ``folder`` (call after ``env.reset``)."""
    meta = {
        "config_name": cfg.name if cfg is not None else env.network.name,
        "run": str(run),
        "sim_step": repr(env.sim_params.sim_step),
        "sims_per_step": str(env.env_params.sims_per_step),
        "record_every": "1",
        **network_metadata(env.k),
    }
    attachments: dict[str, bytes] = {}
    if cfg is not None:
        meta["config"] = dump_config(cfg)
        attachments["config.yaml"] = meta["config"].encode()
    net_file = getattr(env.k, "net_file", None)
    if net_file is not None:
        attachments["network.net.xml"] = Path(net_file).read_bytes()
    return McapRecorder(folder / f"run_{run}.mcap", metadata=meta, attachments=attachments)


def flow_emission_path(emission_path: str, network_name: str, run: int) -> Path:
    """Flow's file of run ``run``: ``<emission_path>/<network_name>-<run>_emission.csv``."""
    return Path(emission_path) / f"{network_name}-{run}_emission.csv"


def flow_emission_csv(mcap_path: Path, out: Path, sim_step: float) -> int:
    """Write Flow's emission CSV of one run from its log; returns the number of rows.

    As Flow's: rows grouped by vehicle (in order of first appearance), then by time; ``time``
    counts from 0 at reset (``round(step * sim_step, 2)``, warm-up included); ``headway`` is
    1000 without a leader, ``leader_id`` / ``follower_id`` empty without one and
    ``leader_rel_speed`` is then Flow's ``-1001 - speed``; ``road_grade`` is 0.
    flowrun logs one commanded acceleration (with noise and fail-safe, as applied), so the
    four ``target_accel_*`` columns hold it (they differ in Flow only for a controller with
    noise or a fail-safe); where no controller commanded the car they hold the realised
    acceleration, as Flow's ``get_accel`` falls back to. The file is replaced atomically.
    """
    from flowrun.recording import open_log

    rows: dict[str, list[list[object]]] = {}
    for frame in open_log(mcap_path).frames():
        n = len(frame.ids)
        if n == 0:
            continue
        t = round(frame.step * sim_step, 2)
        index = {vid: i for i, vid in enumerate(frame.ids)}
        follower = [""] * n
        for i, leader in enumerate(frame.leader):
            j = index.get(leader)
            if j is not None:
                follower[j] = frame.ids[i]
        for i, vid in enumerate(frame.ids):
            speed, real = float(frame.speed[i]), float(frame.accel_real[i])
            cmd = float(frame.accel_cmd[i])
            target = real if math.isnan(cmd) else cmd
            leader = frame.leader[i]
            j = index.get(leader)
            headway = float(frame.headway[i])
            rows.setdefault(vid, []).append([
                t, vid, float(frame.x[i]), float(frame.y[i]), speed,
                FLOW_NO_GAP if math.isinf(headway) else headway, leader,
                target, target, target, target, real, 0, frame.edges[i], int(frame.lanes[i]),
                float(frame.odometer[i]), float(frame.lane_pos[i]), follower[i],
                (float(frame.speed[j]) if j is not None else FLOW_ERROR) - speed,
            ])  # fmt: skip
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.partial")
    try:
        with open(tmp, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(FLOW_EMISSION_COLUMNS)
            for vehicle_rows in rows.values():
                writer.writerows(vehicle_rows)
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    count = sum(len(r) for r in rows.values())
    log.info("wrote %s (%d rows)", out, count)
    return count


#: Flow's ``emission_to_csv`` columns, in Flow's order, and the SUMO ``<vehicle>`` attribute
#: each comes from.
_XML_COLUMNS: tuple[tuple[str, str, bool], ...] = (
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
    *(c for c, _, _ in _XML_COLUMNS),
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
        for column, attr, numeric in _XML_COLUMNS:
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
