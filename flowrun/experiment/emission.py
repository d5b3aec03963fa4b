"""``Experiment.run(convert_to_csv=True)``: per-step vehicle states as CSV, as Flow wrote them.

Flow's simulation kernel kept every vehicle's state at every step and wrote it, at the end of
run ``i``, to ``<emission_path>/<network name>-<i>_emission.csv`` (:data:`FLOW_EMISSION_COLUMNS`).
flowrun logs each run to MCAP (in a fresh folder under ``emission_path``) and writes Flow's
file from that log (:func:`flow_emission_csv`).
"""

from __future__ import annotations

import csv
import logging
import math
import os
from datetime import UTC, datetime
from pathlib import Path

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
