"""Replay library: summary, comparison, CSV export, time-space data, wave drift, plots."""

from __future__ import annotations

import csv
import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from flowrun.recording import McapLog, McapRecorder, open_log
from flowrun.recording.synthetic import ring_frames, step_stats
from flowrun.replay import (
    CSV_COLUMNS,
    compare,
    plot_speeds,
    plot_time_space,
    plot_vehicle_speeds,
    summarize,
    time_space_data,
    to_csv,
    wave_drift,
)

META = {"config_name": "ring", "seed": "3", "flowrun_version": "0.1.0", "sumo_version": "1.28"}


def _record(path: Path, steps: int = 300, wave_speed: float = -4.0, **kw: object) -> list:
    pairs = []
    for frame, stats in ring_frames(22, steps, wave_speed=wave_speed, **kw):  # type: ignore[arg-type]
        if frame.step == 100:  # one collision and one teleport somewhere in the run
            stats = dataclasses.replace(stats, collisions=1, teleports=2)
        pairs.append((frame, stats))
    with McapRecorder(path, metadata=META, attachments={"config.yaml": b"name: ring\n"}) as rec:
        for frame, stats in pairs:
            rec.write(frame, stats)
    return pairs


@pytest.fixture
def logged(tmp_path: Path) -> tuple[McapLog, list]:
    pairs = _record(tmp_path / "ring.mcap")
    return open_log(tmp_path / "ring.mcap"), pairs


def test_summary_speeds_follow_the_documented_definitions(logged: tuple[McapLog, list]) -> None:
    log, pairs = logged
    s = summarize(log)
    speeds = np.array([f.speed for f, _ in pairs])  # steps x vehicles
    assert s.mean_speed == pytest.approx(speeds.mean(axis=1).mean(), rel=1e-12)
    assert s.min_speed == speeds.min() and s.max_speed == speeds.max()
    assert s.speed_std == pytest.approx(speeds.std(axis=1).mean(), rel=1e-12)
    assert s.logged_steps == 300 and s.sim_steps == 300
    assert s.duration_s == pytest.approx(30.0)
    assert s.vehicles_by_type == {"idm": 21, "rl": 1} and s.rl_vehicles == 1
    assert (s.collisions, s.teleports) == (1, 2)
    assert s.episode_return == pytest.approx(sum(st.reward for _, st in pairs))
    assert s.config_name == "ring" and s.seed == "3"
    assert s.versions == {"flowrun_version": "0.1.0", "sumo_version": "1.28"}


def test_summary_of_a_window_and_vehicle_subset(logged: tuple[McapLog, list]) -> None:
    log, pairs = logged
    s = summarize(log, start_s=10.0, end_s=19.95, vehicles=["idm_5"])
    expect = [f.speed[5] for f, _ in pairs if 10.0 <= f.time <= 19.95]
    assert s.logged_steps == len(expect) == 100
    assert s.mean_speed == pytest.approx(np.mean(expect))
    assert s.speed_std == 0.0
    assert s.vehicles_by_type == {"idm": 1}


def test_return_is_none_without_finite_rewards(tmp_path: Path) -> None:
    _record(tmp_path / "h.mcap", steps=20, num_rl=0)
    assert summarize(open_log(tmp_path / "h.mcap")).episode_return is None


def test_compare_puts_two_runs_side_by_side(tmp_path: Path) -> None:
    _record(tmp_path / "a.mcap", steps=100)
    _record(tmp_path / "b.mcap", steps=100, v_free=8.0)
    table = compare(open_log(tmp_path / "a.mcap"), open_log(tmp_path / "b.mcap"))
    a, b, delta = table["mean speed"]
    assert a != b and float(delta) == pytest.approx(2.0, abs=0.1)
    assert table["run"][0].endswith("a.mcap") and table["run"][1].endswith("b.mcap")


def test_csv_has_flow_columns_and_one_row_per_vehicle_step(
    logged: tuple[McapLog, list], tmp_path: Path
) -> None:
    log, pairs = logged
    out = tmp_path / "emission.csv"
    rows = to_csv(log, out)
    with open(out, newline="") as f:
        data = list(csv.DictReader(f))
    assert tuple(data[0].keys()) == CSV_COLUMNS
    assert rows == len(data) == 22 * 300
    got = np.array([float(r["speed"]) for r in data])
    np.testing.assert_array_equal(got, np.concatenate([f.speed for f, _ in pairs]))
    first = {r["id"]: r for r in data[:22]}
    assert first["idm_1"]["leader_id"] == "idm_2" and first["idm_2"]["follower_id"] == "idm_1"
    assert first["rl_0"]["type"] == "rl" and first["idm_3"]["road_grade"] == "0"


def test_csv_writes_nan_as_empty_and_inf_as_inf(tmp_path: Path) -> None:
    frame, _ = next(ring_frames(3, 1))
    headway, accel = frame.headway.copy(), frame.accel_cmd.copy()
    headway[0], accel[1] = math.inf, math.nan
    leader = ["", *frame.leader[1:]]
    frame = dataclasses.replace(frame, headway=headway, accel_cmd=accel, leader=leader)
    with McapRecorder(tmp_path / "x.mcap", metadata={}, attachments={}) as rec:
        rec.write(frame, step_stats(frame))
    to_csv(open_log(tmp_path / "x.mcap"), tmp_path / "x.csv")
    with open(tmp_path / "x.csv", newline="") as f:
        data = list(csv.DictReader(f))
    assert data[0]["headway"] == "inf" and data[0]["leader_rel_speed"] == ""
    assert data[1]["target_accel"] == ""


def test_time_space_data_shows_a_backward_wave(logged: tuple[McapLog, list]) -> None:
    log, _ = logged
    times, positions, speeds, ids = time_space_data(log)
    assert times.shape == positions.shape == speeds.shape == ids.shape == (22 * 300,)
    assert set(ids.tolist()) == {f"idm_{i}" for i in range(1, 22)} | {"rl_0"}
    drift = wave_drift(times, positions, speeds, ring_length=230.0)
    assert drift < 0
    assert drift == pytest.approx(-4.0, abs=0.1)


def test_wave_drift_tracks_a_forward_moving_slow_zone(tmp_path: Path) -> None:
    _record(tmp_path / "f.mcap", steps=300, wave_speed=2.0, dip=2.0)
    t, p, v, _ = time_space_data(open_log(tmp_path / "f.mcap"))
    assert wave_drift(t, p, v, 230.0) == pytest.approx(2.0, abs=0.3)


def test_wave_drift_is_nan_for_uniform_flow() -> None:
    t = np.repeat(np.arange(10.0), 5)
    p = np.tile(np.linspace(0, 200, 5), 10)
    assert math.isnan(wave_drift(t, p, np.full(50, 3.0), 230.0))


def test_plots_are_written(logged: tuple[McapLog, list], tmp_path: Path) -> None:
    log, _ = logged
    outs = [
        plot_time_space(log, tmp_path / "p" / "ts.png"),
        plot_speeds([log, log], tmp_path / "p" / "speeds.png"),
        plot_vehicle_speeds(log, tmp_path / "p" / "traces.png"),
    ]
    for out in outs:
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert out.stat().st_size > 10_000


def test_vehicles_leaving_mid_run_are_all_counted_and_filtered(tmp_path: Path) -> None:
    pairs = list(ring_frames(6, 40))
    path = tmp_path / "roster.mcap"
    with McapRecorder(path, metadata={}, attachments={}) as rec:
        for frame, _ in pairs:
            if frame.step >= 20:  # idm_5 leaves, a new car "extra" of type "hdv" takes its slot
                ids, types = list(frame.ids), list(frame.types)
                ids[5], types[5] = "extra", "hdv"
                frame = dataclasses.replace(frame, ids=ids, types=types)
            rec.write(frame, step_stats(frame))
    log = open_log(path)
    assert summarize(log).vehicles_by_type == {"hdv": 1, "idm": 5, "rl": 1}
    got = [f.ids for f in log.frames(vehicles=["extra", "idm_5"])]
    assert got == [["idm_5"]] * 20 + [["extra"]] * 20
    _, _, _, extra_ids = time_space_data(log, vehicles=["extra"])
    assert extra_ids.tolist() == ["extra"] * 20
