"""Write a clean, indexed copy of whatever a (possibly damaged) flowrun log still holds."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from flowrun.errors import RecordingError
from flowrun.recording.atomic import new_file
from flowrun.recording.mcap_file import McapWriter
from flowrun.recording.reader import McapLog, open_log
from flowrun.recording.schema import VEHICLES_TOPIC
from flowrun.recording.writer import CHUNK_SIZE, PROFILE, media_type

REPAIR_METADATA = "flowrun_repair"
"""Metadata record of a repaired copy of a damaged log: ``source`` (file name), ``lost``
(one line) and ``details`` (one line per damaged part)."""


@dataclass(frozen=True)
class RepairReport:
    """What :func:`repair` recovered.

    Attributes:
        in_path: the damaged (or intact) input.
        out_path: the clean copy written.
        salvaged: whether the input was damaged/unfinished.
        input_bytes: size of the input, bytes.
        recovered_bytes: bytes of the input that could be used.
        messages: messages copied (all topics).
        frames: ``/flowrun/vehicles`` messages copied (logged steps).
        end_time: last simulation time copied, s (``None`` if nothing was copied).
        damage: what the input lost, one line per damaged part (empty when intact).
    """

    in_path: Path
    out_path: Path
    salvaged: bool
    input_bytes: int
    recovered_bytes: int
    messages: int
    frames: int
    end_time: float | None
    damage: tuple[str, ...] = ()


def repair(in_path: str | os.PathLike[str], out_path: str | os.PathLike[str]) -> RepairReport:
    """Copy everything readable in ``in_path`` into a new MCAP with summary and footer.

    The copy is written to a ``.partial`` file beside ``out_path`` and renamed only when
    complete: an interrupted repair leaves no file under ``out_path``, and the input is only
    read. A copy of a damaged log holds a :data:`REPAIR_METADATA` record saying what was lost.

    Raises:
        RecordingError: the input is not a flowrun log, ``out_path`` exists (nothing is
            overwritten) or cannot be written.
    """
    src, dst = Path(in_path), Path(out_path)
    if dst.exists() and dst.resolve() == src.resolve():
        raise RecordingError(f"--repair output {dst} is the input file; choose another path")
    log = open_log(src)
    with new_file(dst, "the repaired copy") as tmp, open(tmp, "wb") as stream:
        writer = McapWriter(
            stream, profile=PROFILE, library="flowrun-repair", chunk_size=CHUNK_SIZE
        )
        for name, data in log.all_metadata.items():
            writer.add_metadata(name, data, checksum=True)
        for name, blob in log.attachments.items():
            writer.add_attachment(name, media_type(name), blob)
        messages, frames, end_ns = _copy_messages(log, writer)
        log.check_data_section()
        if log.damage:  # the copy reads as intact: it says what its source lost
            lost = {"source": src.name, "lost": log.damage.short()}
            lost["details"] = "\n".join(log.damage.describe())
            writer.add_metadata(REPAIR_METADATA, lost, checksum=True)
        writer.finish()
        os.fsync(stream.fileno())
    return RepairReport(
        in_path=src,
        out_path=dst,
        salvaged=log.salvaged,
        input_bytes=log.file_bytes,
        recovered_bytes=log.recovered_bytes,
        messages=messages,
        frames=frames,
        end_time=None if end_ns is None else end_ns / 1e9,
        damage=tuple(log.damage.describe()),
    )


def _copy_messages(log: McapLog, writer: McapWriter) -> tuple[int, int, int | None]:
    """Every readable message of ``log`` into ``writer``, its schemas and channels registered
    anew on first use; returns the messages copied, the vehicle frames among them and the
    last log time (ns; ``None`` without messages)."""
    messages = frames = 0
    end_ns: int | None = None
    schema_ids: dict[int, int] = {}
    channel_ids: dict[int, int] = {}
    for schema, channel, message in log.messages():
        if channel.id not in channel_ids:
            new_schema = 0
            if schema is not None:
                if schema.id not in schema_ids:
                    schema_ids[schema.id] = writer.register_schema(
                        schema.name, schema.encoding, schema.data
                    )
                new_schema = schema_ids[schema.id]
            channel_ids[channel.id] = writer.register_channel(
                channel.topic, channel.message_encoding, new_schema, dict(channel.metadata)
            )
        writer.add_message(
            channel_ids[channel.id],
            message.log_time,
            message.data,
            message.publish_time,
            message.sequence,
        )
        messages += 1
        frames += channel.topic == VEHICLES_TOPIC
        end_ns = message.log_time if end_ns is None else max(end_ns, message.log_time)
    return messages, frames, end_ns
