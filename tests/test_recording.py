"""MCAP recording: round trip, thinning, filtering, salvage of damaged files, repair."""

from __future__ import annotations

import dataclasses
import logging
import math
import os
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from flowrun.errors import RecordingError
from flowrun.recording import (
    STATS_TOPIC,
    VEHICLES_TOPIC,
    McapRecorder,
    VehicleFrame,
    open_log,
    repair,
)
from flowrun.recording.frames import StepStats
from flowrun.recording.synthetic import ring_frames, step_stats

META = {"flowrun_version": "0.1.0", "seed": "7", "config_name": "sugiyama", "config": "name: x\n"}
ATTACH = {"config.yaml": b"name: x\n", "network.net.xml": b"<net/>"}


def _with_non_finite(frame: VehicleFrame) -> VehicleFrame:
    headway = frame.headway.copy()
    accel_cmd = frame.accel_cmd.copy()
    leader = list(frame.leader)
    headway[0] = math.inf
    leader[0] = ""
    accel_cmd[1] = math.nan
    return dataclasses.replace(frame, headway=headway, accel_cmd=accel_cmd, leader=leader)


def _write(path: Path, steps: int = 200, record_every: int = 1, **kwargs: object) -> list:
    pairs = [(_with_non_finite(f), s) for f, s in ring_frames(22, steps)]
    with McapRecorder(
        path,
        metadata=META,
        attachments=ATTACH,
        record_every=record_every,
        **kwargs,  # type: ignore[arg-type]
    ) as rec:
        for frame, stats in pairs:
            rec.write(frame, stats)
    return pairs


def _assert_frames_equal(a: VehicleFrame, b: VehicleFrame) -> None:
    for f in dataclasses.fields(VehicleFrame):
        va, vb = getattr(a, f.name), getattr(b, f.name)
        if isinstance(va, np.ndarray):
            np.testing.assert_array_equal(np.asarray(vb), va, err_msg=f.name)
            assert np.asarray(vb).dtype.kind == va.dtype.kind, f.name
        else:
            assert list(vb) == list(va) if isinstance(va, list) else vb == va, f.name


def test_round_trip_keeps_every_column_and_non_finite_values(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    pairs = _write(path, steps=50)
    log = open_log(path)
    frames = list(log.frames())
    assert len(frames) == 50
    for (orig, _), back in zip(pairs, frames, strict=True):
        _assert_frames_equal(orig, back)
    assert math.isinf(frames[3].headway[0]) and frames[3].leader[0] == ""
    assert math.isnan(frames[3].accel_cmd[1])
    stats = list(log.stats())
    for (_, orig_stats), back_stats in zip(pairs, stats, strict=True):
        for f in dataclasses.fields(StepStats):
            a, b = getattr(orig_stats, f.name), getattr(back_stats, f.name)
            assert a == b or (math.isnan(a) and math.isnan(b)), f.name
    assert log.metadata == META
    assert log.attachments == ATTACH
    assert not log.salvaged and log.recovered_bytes == path.stat().st_size
    assert log.frame_count == 50


def test_log_time_is_simulation_time_in_ns(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    pairs = _write(path, steps=20)
    with open(path, "rb") as f:
        msgs = list(make_reader(f).iter_messages(topics=[VEHICLES_TOPIC]))
    assert [m.log_time for _, _, m in msgs] == [round(fr.time * 1e9) for fr, _ in pairs]
    assert all(m.publish_time == m.log_time for _, _, m in msgs)


def test_channels_are_protobuf_with_descriptor_schemas(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    _write(path, steps=5)
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    topics = {c.topic: c for c in summary.channels.values()}
    assert set(topics) == {VEHICLES_TOPIC, STATS_TOPIC}
    for channel in topics.values():
        assert channel.message_encoding == "protobuf"
        assert summary.schemas[channel.schema_id].encoding == "protobuf"
    assert summary.schemas[topics[VEHICLES_TOPIC].schema_id].name == "flowrun.VehicleFrame"


def test_record_every_keeps_multiples_of_n(tmp_path: Path) -> None:
    path = tmp_path / "thin.mcap"
    _write(path, steps=100, record_every=10)
    log = open_log(path)
    assert [f.step for f in log.frames()] == list(range(0, 100, 10))
    assert [s.step for s in log.stats()] == list(range(0, 100, 10))


def test_time_range_and_vehicle_filter(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    _write(path, steps=200, chunk_size=20_000)
    log = open_log(path)
    frames = list(log.frames(start_s=5.0, end_s=10.0, vehicles=["idm_3", "rl_0", "nope"]))
    assert [f.step for f in frames] == list(range(50, 101))
    assert all(f.ids == ["rl_0", "idm_3"] for f in frames)
    assert all(f.speed.shape == (2,) and f.is_rl.tolist() == [True, False] for f in frames)
    assert [s.step for s in log.stats(start_s=19.0)] == list(range(190, 200))
    assert list(log.frames(start_s=30.0)) == []


def test_close_is_idempotent_and_write_after_close_fails(tmp_path: Path) -> None:
    rec = McapRecorder(tmp_path / "a.mcap", metadata={}, attachments={})
    frame, stats = next(ring_frames(5, 1))
    rec.write(frame, stats)
    rec.close()
    rec.finish()
    with pytest.raises(RecordingError):
        rec.write(frame, stats)
    assert len(list(open_log(tmp_path / "a.mcap").frames())) == 1


def test_unclosed_recorder_leaves_salvageable_file(tmp_path: Path) -> None:
    path = tmp_path / "killed.mcap"
    rec = McapRecorder(path, metadata=META, attachments=ATTACH, flush_every_s=0.0)
    for frame, stats in ring_frames(22, 30):
        rec.write(frame, stats)
    # Simulate a killed process: the footer is never written (no close()).
    log = open_log(path)
    assert log.salvaged
    assert len(list(log.frames())) == 30
    assert log.metadata == META and log.attachments == ATTACH
    rec.close()


@pytest.mark.parametrize("fraction", [0.35, 0.5, 0.77, 0.93, 0.999])
def test_truncated_file_is_salvaged_up_to_the_damage(
    tmp_path: Path, fraction: float, caplog: pytest.LogCaptureFixture
) -> None:
    full = tmp_path / "full.mcap"
    _write(full, steps=300, chunk_size=30_000)
    data = full.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * fraction)])
    with caplog.at_level(logging.WARNING):
        log = open_log(cut)
    assert log.salvaged
    assert 0 < log.recovered_bytes <= cut.stat().st_size
    assert "salvaged" in caplog.text
    frames = list(log.frames())
    assert 0 < len(frames) <= 300
    assert [f.step for f in frames] == list(range(len(frames)))
    assert len(frames) <= len(list(log.stats())) <= len(frames) + 1
    assert log.metadata == META
    # time filtering still works on a salvaged file
    late = list(log.frames(start_s=frames[-1].time))
    assert [f.step for f in late] == [frames[-1].step]


def test_repair_writes_an_indexed_copy(tmp_path: Path) -> None:
    full = tmp_path / "full.mcap"
    _write(full, steps=300, chunk_size=30_000)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(full.read_bytes()[: int(full.stat().st_size * 0.6)])
    fixed = tmp_path / "fixed.mcap"
    report = repair(cut, fixed)
    assert report.salvaged and report.frames > 0
    with open(fixed, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.chunk_indexes
    log = open_log(fixed)
    assert not log.salvaged
    assert log.frame_count == report.frames == len(list(open_log(cut).frames()))
    assert log.metadata == META and log.attachments == ATTACH


def test_text_file_is_not_a_log(tmp_path: Path) -> None:
    path = tmp_path / "notes.mcap"
    path.write_text("hello, I am not MCAP\n")
    with pytest.raises(RecordingError, match="not an MCAP file"):
        open_log(path)


def test_missing_file_is_reported(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match="no such file"):
        open_log(tmp_path / "nope.mcap")


def test_a_fifo_is_not_a_log_and_is_not_called_missing(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)  # opening it to read would block
    with pytest.raises(RecordingError, match=r"pipe\.mcap: not a regular file"):
        open_log(fifo)


def test_mcap_without_flowrun_topics_is_rejected(tmp_path: Path) -> None:
    from mcap.writer import Writer

    path = tmp_path / "other.mcap"
    with open(path, "wb") as stream:
        w = Writer(stream)
        w.start()
        sid = w.register_schema("x", "jsonschema", b"{}")
        cid = w.register_channel("/camera", "json", sid)
        w.add_message(cid, 0, b"{}", 0)
        w.finish()
    with pytest.raises(RecordingError, match="no /flowrun/vehicles topic"):
        open_log(path)


def test_file_cut_before_any_data_is_an_error(tmp_path: Path) -> None:
    full = tmp_path / "full.mcap"
    _write(full, steps=10)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(full.read_bytes()[:40])
    with pytest.raises(RecordingError):
        open_log(cut)


def test_truncation_at_any_offset_never_crashes(tmp_path: Path) -> None:
    full = tmp_path / "full.mcap"
    _write(full, steps=120, chunk_size=15_000)
    data = full.read_bytes()
    counts = []
    for cut_at in np.linspace(9, len(data) - 1, 37).astype(int):
        cut = tmp_path / f"cut{cut_at}.mcap"
        cut.write_bytes(data[:cut_at])
        try:
            log = open_log(cut)
        except RecordingError:
            counts.append(0)  # cut before the first complete chunk: one clear error
            continue
        counts.append(len(list(log.frames())))
        assert log.salvaged
    assert counts == sorted(counts) and 0 < counts[-1] <= 120


def test_roster_version_counts_changes_of_values_not_of_objects(tmp_path: Path) -> None:
    path = tmp_path / "roster.mcap"
    frames = [f for f, _ in ring_frames(4, 8)]
    frames[2] = dataclasses.replace(frames[2], ids=list(frames[2].ids))  # same values
    frames[3] = dataclasses.replace(frames[3], is_rl=frames[3].is_rl.copy())  # same values
    frames[4] = dataclasses.replace(frames[4], ids=["a", "b", "c", "d"])
    frames[5] = dataclasses.replace(frames[5], ids=["a", "b", "c", "d"])  # new list, same
    frames[6] = dataclasses.replace(frames[6], is_rl=np.ones(4, dtype=bool))
    with McapRecorder(path, metadata={}, attachments={}) as rec:
        for frame in frames:
            rec.write(frame, step_stats(frame))
    log = open_log(path)
    assert [m.roster_version for m in log.vehicle_messages()] == [1, 1, 1, 1, 2, 2, 3, 4]
    assert log.all_metadata["flowrun_roster"] == {"rosters": "4"}
    assert [f.ids for f in log.frames()][4] == ["a", "b", "c", "d"]
