"""flowrun's own MCAP writer, checked with the mcap library's readers and the spec's CRCs."""

from __future__ import annotations

import io
import itertools
import struct
import zlib
from pathlib import Path

import pytest
from mcap.exceptions import EndOfFile
from mcap.reader import make_reader
from mcap.records import Attachment, Channel, DataEnd, Message, Schema, SummaryOffset
from mcap.stream_reader import StreamReader

from flowrun.errors import RecordingError
from flowrun.recording import McapRecorder, open_log
from flowrun.recording.mcap_file import MAGIC, OP_ATTACHMENT_INDEX, McapWriter, record
from flowrun.recording.synthetic import ring_frames

ATTACHMENT = ("config.yaml", "application/yaml", b"name: ring\n" * 50)
METADATA = {"seed": "7", "config_name": "ring", "unicode": "véhicule 车"}


def write_sample(steps: int = 300) -> tuple[bytes, list[tuple[str, int, bytes]]]:
    """Two topics at 10 Hz (ns log times from 0.1 s), small chunks; what was added, in order."""
    stream = io.BytesIO()
    added = []
    writer = McapWriter(stream, profile="flowrun", chunk_size=3_000)
    writer.add_metadata("flowrun", METADATA)
    writer.add_attachment(*ATTACHMENT, log_time=5, create_time=6)
    schema_id = writer.register_schema("flowrun.Test", "protobuf", b"\x0a\x03abc")
    fast = writer.register_channel("/fast", "protobuf", schema_id)
    slow = writer.register_channel("/slow", "json", 0, {"unit": "m/s"})
    for step in range(1, steps + 1):
        stamp = step * 100_000_000
        added.append(("/fast", stamp, bytes([step % 256]) * (step % 40)))
        writer.add_message(fast, stamp, added[-1][2], stamp, step)
        if step % 7 == 0:
            added.append(("/slow", stamp, b'{"v": %d}' % step))
            writer.add_message(slow, stamp, added[-1][2], stamp + 1, step)
    writer.finish()
    writer.finish()  # twice is harmless
    return stream.getvalue(), added


def test_mcap_library_reads_summary_indexes_and_messages() -> None:
    data, added = write_sample()
    reader = make_reader(io.BytesIO(data), validate_crcs=True)
    summary = reader.get_summary()
    assert summary is not None and summary.statistics is not None
    stats = summary.statistics
    assert stats.message_count == len(added)
    assert stats.channel_message_counts == {1: 300, 2: 300 // 7}
    assert (stats.message_start_time, stats.message_end_time) == (100_000_000, 30_000_000_000)
    assert (stats.schema_count, stats.channel_count) == (1, 2)
    assert (stats.attachment_count, stats.metadata_count) == (1, 1)
    assert stats.chunk_count == len(summary.chunk_indexes) > 5
    assert {c.topic: c.metadata for c in summary.channels.values()}["/slow"] == {"unit": "m/s"}
    assert summary.schemas[1].data == b"\x0a\x03abc"
    # chunk indexes cover the messages in order, without gaps or overlaps
    indexes = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    assert indexes[0].message_start_time == 100_000_000
    assert indexes[-1].message_end_time == 30_000_000_000
    for before, after in itertools.pairwise(indexes):
        assert before.message_end_time <= after.message_start_time
        assert before.chunk_start_offset + before.chunk_length <= after.chunk_start_offset
    got = [(c.topic, m.log_time, m.data) for _, c, m in reader.iter_messages()]
    assert got == added
    window = list(
        reader.iter_messages(topics=["/slow"], starting_at=7 * 10**8, ending_at=21 * 10**8)
    )
    assert [m.sequence for _, _, m in window] == [7, 14, 21]
    assert all(m.publish_time == m.log_time + 1 for _, _, m in window)
    attachments = list(reader.iter_attachments())
    assert [(a.name, a.media_type, a.data, a.log_time, a.create_time) for a in attachments] == [
        (*ATTACHMENT, 5, 6)
    ]
    assert [(m.name, m.metadata) for m in reader.iter_metadata()] == [("flowrun", METADATA)]
    header = reader.get_header()
    assert (header.profile, header.library) == ("flowrun", "flowrun")


class _NoSeek(io.RawIOBase):
    def __init__(self, data: bytes) -> None:
        self._data = io.BytesIO(data)

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: bytearray) -> int:  # type: ignore[override]
        chunk = self._data.read(len(buffer))
        buffer[: len(chunk)] = chunk
        return len(chunk)


def test_stream_readers_validate_every_crc_and_see_every_message() -> None:
    data, added = write_sample()
    records = list(StreamReader(io.BytesIO(data), validate_crcs=True).records)
    messages = [r for r in records if isinstance(r, Message)]
    assert [m.data for m in messages] == [d for _, _, d in added]
    assert sum(isinstance(r, DataEnd) for r in records) == 1
    assert sum(isinstance(r, Attachment) for r in records) == 1
    # schemas/channels precede the first chunk; the summary repeats them
    assert [type(r) for r in records[3:6]] == [Schema, Channel, Channel]
    reader = make_reader(_NoSeek(data), validate_crcs=True)  # type: ignore[arg-type]  # non-seeking
    assert [m.data for _, _, m in reader.iter_messages()] == [d for _, _, d in added]


def test_attachment_and_summary_crcs_follow_the_spec() -> None:
    data, _ = write_sample()
    footer = data[-len(MAGIC) - 29 : -len(MAGIC)]
    opcode, length, summary_start, offset_start, summary_crc = struct.unpack("<BQQQI", footer)
    assert (opcode, length) == (0x02, 20)
    assert summary_crc == zlib.crc32(data[summary_start : -len(MAGIC) - 4])
    offsets = [
        r
        for r in StreamReader(io.BytesIO(data[offset_start:]), skip_magic=True).records
        if isinstance(r, SummaryOffset)
    ]
    assert {o.group_opcode for o in offsets} == {0x03, 0x04, 0x0A, 0x0B, 0x08, 0x0D}
    for group in offsets:  # each group starts with a record of its opcode
        assert data[group.group_start] == group.group_opcode
    (attachment_index,) = [o for o in offsets if o.group_opcode == OP_ATTACHMENT_INDEX]
    index_offset = attachment_index.group_start + 9
    offset, length = struct.unpack_from("<QQ", data, index_offset)
    rec = data[offset : offset + length]
    assert rec[0] == 0x09
    assert struct.unpack("<I", rec[-4:])[0] == zlib.crc32(rec[9:-4])


def test_the_same_input_gives_the_same_file() -> None:
    assert write_sample()[0] == write_sample()[0]


def test_an_empty_file_is_valid() -> None:
    empty = io.BytesIO()
    McapWriter(empty).finish()
    summary = make_reader(io.BytesIO(empty.getvalue())).get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == 0 and not summary.chunk_indexes
    assert empty.getvalue().startswith(MAGIC) and empty.getvalue().endswith(MAGIC)


def test_flushed_data_is_in_the_file_before_finish() -> None:
    stream = io.BytesIO()
    writer = McapWriter(stream)
    channel = writer.register_channel("/t", "json")
    for i in range(10):
        writer.add_message(channel, i, b"%d" % i, i)
    writer.flush()
    writer.add_message(channel, 10, b"not flushed", 10)
    records = StreamReader(io.BytesIO(stream.getvalue()), validate_crcs=True).records
    got = []
    with pytest.raises(EndOfFile):  # the file simply ends: no Data End, no footer
        for r in records:
            if isinstance(r, Message):
                got.append(r.data)
    assert got == [b"%d" % i for i in range(10)]
    writer.finish()


def test_message_data_is_copied_and_bad_calls_are_refused() -> None:
    stream = io.BytesIO()
    writer = McapWriter(stream)
    channel = writer.register_channel("/t", "json")
    buffer = bytearray(b"before")
    writer.add_message(channel, 1, buffer, 1)  # type: ignore[arg-type]
    buffer[:] = b"after!"
    with pytest.raises(RecordingError, match="not registered"):
        writer.add_message(channel + 1, 2, b"x", 2)
    with pytest.raises(RecordingError, match="schema 3"):
        writer.register_channel("/u", "json", schema_id=3)
    writer.finish()
    with pytest.raises(RecordingError, match="finished"):
        writer.add_message(channel, 3, b"x", 3)
    with pytest.raises(RecordingError, match="finished"):
        writer.add_metadata("late", {})
    reader = make_reader(io.BytesIO(stream.getvalue()))
    assert [m.data for _, _, m in reader.iter_messages()] == [b"before"]


def test_record_is_opcode_length_content() -> None:
    assert (
        record(0x0F, b"\x01\x02\x03\x04")
        == b"\x0f" + (4).to_bytes(8, "little") + b"\x01\x02\x03\x04"
    )


def test_recorder_file_cut_after_a_flush_is_salvaged_up_to_it(tmp_path: Path) -> None:
    path = tmp_path / "killed.mcap"
    rec = McapRecorder(path, metadata=METADATA, attachments={}, flush_every_s=3600.0)
    pairs = list(ring_frames(22, 60))
    for frame, stats in pairs[:40]:
        rec.write(frame, stats)
    rec.flush()
    for frame, stats in pairs[40:]:
        rec.write(frame, stats)  # stays in the open chunk: lost if the process dies now
    log = open_log(path)  # read while the recorder is still open: no footer yet
    assert log.salvaged and log.metadata == METADATA
    assert [f.step for f in log.frames()] == list(range(40))
    rec.close()
    rec.close()
    closed = open_log(path)
    assert not closed.salvaged and closed.frame_count == 60


class _FullDisk(io.BytesIO):
    def __init__(self, room: int) -> None:
        super().__init__()
        self.room = room

    def write(self, data: bytes) -> int:  # type: ignore[override]
        if self.tell() + len(data) > self.room:
            raise OSError(28, "No space left on device")
        return super().write(data)


def test_a_failing_chunk_write_reaches_the_caller() -> None:
    writer = McapWriter(_FullDisk(room=2_000), chunk_size=1_000)
    channel = writer.register_channel("/t", "json")
    with pytest.raises(OSError, match="No space"):
        for i in range(100):
            writer.add_message(channel, i, b"x" * 100, i)
        writer.flush()
