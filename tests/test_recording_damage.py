"""Damaged logs (issues 10 and 16): seeded byte flips and truncations all over a real log.

For every damaged copy, through the library: either one clear :class:`RecordingError`, or a
read whose every message equals the intact log's (nothing silently wrong), with the loss
reported in ``log.damage`` whenever a logged step is missing; and when no damage is
reported, the summary and the CSV export equal the intact log's byte for byte.
"""

from __future__ import annotations

import struct
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from flowrun.errors import RecordingError
from flowrun.recording import McapRecorder, open_log, repair
from flowrun.recording.synthetic import ring_frames
from flowrun.replay import summarize, summary_rows, to_csv

META = {"config_name": "ring", "seed": "3", "flowrun_version": "0.1.0", "config": "a: 1\n" * 40}
ATTACH = {"config.yaml": b"name: ring\n" * 20, "network.net.xml": b"<net/>" * 50}
STEPS = 300
VEHICLES = 6
SEED = 16

# MCAP opcodes (https://mcap.dev/spec)
REGIONS = {
    0x01: "header",
    0x03: "schema/channel",
    0x04: "schema/channel",
    0x06: "chunk",
    0x07: "message index",
    0x09: "attachment",
    0x0C: "metadata",
    0x0F: "data end",
}


@dataclass(frozen=True)
class Intact:
    path: Path
    data: bytes
    messages: dict[tuple[str, int], bytes]
    rows: dict[str, str]
    csv: bytes
    regions: dict[str, list[int]]  # region -> byte offsets in it


def _messages(path: Path) -> dict[tuple[str, int], bytes]:
    log = open_log(path)
    return {(ch.topic, m.log_time): m.data for _, ch, m in log.messages()}


def _regions(data: bytes) -> dict[str, list[int]]:
    """Byte offsets of each kind of part, from a walk of the intact file's records."""
    out: dict[str, list[int]] = {"magic": [*range(8), *range(len(data) - 8, len(data))]}
    summary_start = struct.unpack_from("<Q", data, len(data) - 8 - 20)[0]
    pos = 8
    while pos < summary_start:
        opcode, length = struct.unpack_from("<BQ", data, pos)
        end = pos + 9 + length
        if opcode == 0x06:  # header: opcode .. compressed size (61 bytes); then zstd data
            out.setdefault("chunk header", []).extend(range(pos, pos + 61))
            out.setdefault("chunk data", []).extend(range(pos + 61, end))
        else:
            out.setdefault(REGIONS[opcode], []).extend(range(pos, end))
        pos = end
    footer = len(data) - 8 - 29
    out["summary"] = list(range(summary_start, footer))
    out["footer"] = list(range(footer, len(data) - 8))
    return out


@pytest.fixture(scope="module")
def intact(tmp_path_factory: pytest.TempPathFactory) -> Intact:
    path = tmp_path_factory.mktemp("damage") / "intact.mcap"
    with McapRecorder(path, metadata=META, attachments=ATTACH, chunk_size=12_000) as rec:
        for frame, stats in ring_frames(VEHICLES, STEPS):
            rec.write(frame, stats)
    log = open_log(path)
    csv = path.with_suffix(".csv")
    to_csv(log, csv)
    data = path.read_bytes()
    rows = summary_rows(summarize(log))
    del rows["run"]
    return Intact(path, data, _messages(path), rows, csv.read_bytes(), _regions(data))


def _check(intact: Intact, path: Path) -> str:
    """Read a damaged copy every way replay does; returns the outcome's kind."""
    try:
        log = open_log(path)
    except RecordingError as err:
        assert str(err) and "\n" not in str(err)
        return "error"
    rows = summary_rows(summarize(log))
    del rows["run"]  # holds the file name
    csv = path.with_suffix(".csv")
    to_csv(log, csv, overwrite=False)
    got = {(ch.topic, m.log_time): m.data for _, ch, m in log.messages()}
    wrong = [k for k, v in got.items() if intact.messages.get(k) != v]
    assert not wrong, f"{len(wrong)} messages differ from the intact log's, first {wrong[0]}"
    if not log.damage:
        assert rows == intact.rows
        assert csv.read_bytes() == intact.csv
        assert log.metadata == META and log.attachments == ATTACH
        return "intact"
    assert rows["damage"] == log.damage.short() != ""
    vehicles = {k for k in got if k[0] == "/flowrun/vehicles"}
    if len(vehicles) < STEPS:  # a lost step is always reported as lost data
        assert log.damage.data_lost, log.damage.describe()
    # metadata and attachments are intact or left out, never silently changed
    assert log.metadata in (META, {})
    assert all(ATTACH[name] == blob for name, blob in log.attachments.items())
    return "salvaged" if vehicles else "nothing left"


FLIPS = {
    "chunk data": 30,
    "chunk header": 20,
    "message index": 8,
    "metadata": 14,
    "attachment": 8,
    "schema/channel": 8,
    "header": 3,
    "data end": 3,
    "summary": 20,
    "footer": 8,
    "magic": 4,
}


def test_byte_flips_are_detected_or_harmless(
    intact: Intact, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rng = np.random.default_rng(SEED)
    tally: Counter[tuple[str, str]] = Counter()
    for region, count in FLIPS.items():
        offsets = rng.choice(intact.regions[region], size=count, replace=False)
        for i, offset in enumerate(offsets):
            data = bytearray(intact.data)
            data[offset] ^= int(rng.integers(1, 256))
            path = tmp_path / f"{region.replace('/', '_').replace(' ', '_')}_{i}.mcap"
            path.write_bytes(bytes(data))
            tally[(region, _check(intact, path))] += 1
    with capsys.disabled():
        print(f"\nbyte flips ({sum(tally.values())}): {dict(sorted(tally.items()))}")
    # every flip in chunk contents is caught by the chunk CRC; metadata by its own CRC
    assert tally[("chunk data", "intact")] == 0
    assert tally[("metadata", "intact")] == 0
    assert sum(n for (_, kind), n in tally.items() if kind == "error") == 0


def test_byte_flips_in_an_unfinished_log_are_skipped_to_the_next_chunk(
    intact: Intact, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # no summary (a killed run): the data section is scanned, so damaged record headers
    # and lengths must be skipped over by finding the next chunk
    summary_start = struct.unpack_from("<Q", intact.data, len(intact.data) - 28)[0]
    cut = intact.data[:summary_start]
    rng = np.random.default_rng(SEED + 2)
    tally: Counter[tuple[str, str]] = Counter()
    for region in ("chunk header", "message index", "metadata", "attachment", "schema/channel"):
        offsets = rng.choice(intact.regions[region], size=8, replace=False)
        for i, offset in enumerate(offsets):
            data = bytearray(cut)
            data[offset] ^= int(rng.integers(1, 256))
            path = tmp_path / f"{region.replace('/', '_').replace(' ', '_')}_{i}.mcap"
            path.write_bytes(bytes(data))
            tally[(region, _check(intact, path))] += 1
    with capsys.disabled():
        print(f"\nbyte flips in an unfinished log ({sum(tally.values())}): {dict(tally)}")
    assert sum(n for (_, kind), n in tally.items() if kind in ("error", "nothing left")) == 0


def test_truncations_salvage_every_complete_chunk(
    intact: Intact, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rng = np.random.default_rng(SEED + 1)
    size = len(intact.data)
    cuts = sorted({*np.linspace(1, size - 1, 40).astype(int), *rng.integers(1, size, 20)})
    tally: Counter[str] = Counter()
    steps = []
    for cut in cuts:
        path = tmp_path / f"cut_{cut}.mcap"
        path.write_bytes(intact.data[:cut])
        kind = _check(intact, path)
        tally[kind] += 1
        steps.append(0 if kind == "error" else len(list(open_log(path).frames())))
    with capsys.disabled():
        print(f"\ntruncations ({len(cuts)}): {dict(tally)}")
    assert tally["intact"] == 0  # a cut log always says it is cut
    assert steps == sorted(steps) and steps[-1] == STEPS  # cut in the summary: all data


def test_a_damaged_metadata_record_loses_only_the_metadata(intact: Intact, tmp_path: Path) -> None:
    data = bytearray(intact.data)
    at = intact.data.index(b"a: 1\n")  # inside the flowrun record's config value
    data[at] ^= 0x20
    path = tmp_path / "meta.mcap"
    path.write_bytes(bytes(data))
    log = open_log(path)
    assert "flowrun" not in log.all_metadata
    assert [x.part for x in log.damage.losses] == ["metadata"]
    assert "metadata 'flowrun' lost" in log.damage.short()
    assert len(list(log.frames())) == STEPS and not log.damage.data_lost


def test_an_unfinished_log_with_a_broken_metadata_length_still_reads(
    intact: Intact, tmp_path: Path
) -> None:
    # no footer (a killed run) and the first metadata record's length field destroyed: the
    # scan skips to the next chunk, and flowrun's fixed channel ids stand in for the records
    summary_start = struct.unpack_from("<Q", intact.data, len(intact.data) - 28)[0]
    data = bytearray(intact.data[:summary_start])
    meta_at = intact.regions["metadata"][0]
    data[meta_at + 1 : meta_at + 9] = b"\xff" * 8
    path = tmp_path / "killed.mcap"
    path.write_bytes(bytes(data))
    log = open_log(path)
    assert {x.part for x in log.damage.losses} >= {"records", "channels"}
    assert not log.damage.data_lost
    assert log.metadata == {} and log.attachments == {}
    assert len(list(log.frames())) == STEPS
    assert _messages(path).items() <= intact.messages.items()


def test_a_bad_chunk_in_the_middle_costs_that_chunk_only(intact: Intact, tmp_path: Path) -> None:
    chunk_data = intact.regions["chunk data"]
    data = bytearray(intact.data)
    middle = chunk_data[len(chunk_data) // 2]
    data[middle] ^= 0xFF
    path = tmp_path / "middle.mcap"
    path.write_bytes(bytes(data))
    log = open_log(path)
    frames = [f.step for f in log.frames()]
    (loss,) = log.damage.lost_chunks
    assert loss.frames is not None and 0 < loss.frames == STEPS - len(frames)
    assert loss.start_s is not None and loss.end_s is not None
    missing = sorted(set(range(STEPS)) - set(frames))
    assert missing == list(range(missing[0], missing[-1] + 1))  # one contiguous gap
    assert frames[0] == 0 and frames[-1] == STEPS - 1  # before and after it: read
    assert loss.start_s <= missing[0] * 0.1 + 1e-9 and missing[-1] * 0.1 <= loss.end_s + 1e-9


def _copy_with_data_crc(src: Path, dst: Path) -> None:
    """Rewrite a flowrun log with the mcap library, which can store the data section CRC."""
    from mcap.writer import Writer

    log = open_log(src)
    with open(dst, "wb") as stream:
        writer = Writer(stream, enable_data_crcs=True)
        writer.start(profile="flowrun", library="mcap-python")
        ids: dict[int, int] = {}
        for sch, ch, msg in log.messages():
            if ch.id not in ids:
                assert sch is not None
                sid = writer.register_schema(sch.name, sch.encoding, sch.data)
                ids[ch.id] = writer.register_channel(ch.topic, ch.message_encoding, sid)
            writer.add_message(ids[ch.id], msg.log_time, msg.data, msg.publish_time)
        writer.finish()


def test_the_data_section_crc_is_checked_where_the_writer_stored_one(
    intact: Intact, tmp_path: Path
) -> None:
    good = tmp_path / "lib.mcap"
    _copy_with_data_crc(intact.path, good)
    assert not open_log(good).verify()
    data = bytearray(good.read_bytes())
    pos = 8
    while data[pos] != 0x07:  # the first Message Index record: no CRC of its own
        pos += 9 + struct.unpack_from("<Q", data, pos + 1)[0]
    data[pos + 9 + 6 + 4 + 3] ^= 0x01  # a log time in its first entry
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    log = open_log(bad)
    assert not log.damage  # nothing else notices: the index entries are not used
    assert [x.part for x in log.verify().losses] == ["data section"]
    assert _messages(bad) == _messages(good)


def test_a_window_read_does_not_trust_the_times_of_a_damaged_scanned_chunk(
    intact: Intact, tmp_path: Path
) -> None:
    summary_start = struct.unpack_from("<Q", intact.data, len(intact.data) - 28)[0]
    data = bytearray(intact.data[:summary_start])  # unfinished: chunk headers are scanned
    headers = intact.regions["chunk header"]
    middle = headers[61 * (len(headers) // 61 // 2)]  # the first byte of a middle chunk
    data[middle + 9 + 7] ^= 0x40  # message_start_time's top byte (outside the chunk's CRC)
    path = tmp_path / "times.mcap"
    path.write_bytes(bytes(data))
    want = [f.step for f in open_log(intact.path).frames(5.0, 25.0)]
    assert [f.step for f in open_log(path).frames(5.0, 25.0)] == want


def test_zeroed_disk_blocks_are_detected_or_harmless(
    intact: Intact, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a lost 4 KiB sector reads back as zeros: several records damaged at once
    rng = np.random.default_rng(SEED + 3)
    tally: Counter[str] = Counter()
    for i, block in enumerate(rng.choice(len(intact.data) // 4096, size=12, replace=False)):
        data = bytearray(intact.data)
        data[block * 4096 : (block + 1) * 4096] = bytes(4096)
        path = tmp_path / f"zeroed_{i}.mcap"
        path.write_bytes(bytes(data))
        tally[_check(intact, path)] += 1
    with capsys.disabled():
        print(f"\nzeroed 4 KiB blocks (12): {dict(tally)}")
    assert tally["error"] == 0


def test_a_zeroed_start_of_a_finished_log_costs_its_metadata_only(
    intact: Intact, tmp_path: Path
) -> None:
    data = bytearray(intact.data)
    data[:4096] = bytes(4096)  # magic, header, metadata, attachments, first chunk(s)
    path = tmp_path / "start.mcap"
    path.write_bytes(bytes(data))
    log = open_log(path)
    assert {"magic", "metadata"} <= {x.part for x in log.damage.losses}
    assert _messages(path).items() <= intact.messages.items()


def test_a_repaired_copy_reads_clean_and_says_what_its_source_lost(
    intact: Intact, tmp_path: Path
) -> None:
    chunk_data = intact.regions["chunk data"]
    data = bytearray(intact.data)
    data[chunk_data[len(chunk_data) // 3]] ^= 0x10
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(data))
    report = repair(damaged, tmp_path / "fixed.mcap")
    assert report.salvaged and len(report.damage) == 1 and "CRC mismatch" in report.damage[0]
    fixed = open_log(tmp_path / "fixed.mcap")
    assert not fixed.verify()
    assert _messages(tmp_path / "fixed.mcap") == _messages(damaged)
    assert fixed.metadata == META and fixed.attachments == ATTACH
    row = summary_rows(summarize(fixed))["damage"]
    assert row.startswith("none here; repaired from damaged.mcap, which lost: 1 chunk lost (t=")
    with pytest.raises(RecordingError, match="exists"):
        repair(damaged, tmp_path / "fixed.mcap")  # nothing is overwritten
