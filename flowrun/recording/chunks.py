"""A log's chunks: read, decompress, CRC-check and split one, and the messages it holds.

:class:`~flowrun.recording.reader.McapLog` uses these to read an indexed or salvaged log;
nothing here keeps state, so a chunk can be loaded in a worker thread.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from typing import IO, NamedTuple

from mcap.records import Channel, Message, Schema

from flowrun.errors import RecordingError
from flowrun.recording import mcap_records, schema
from flowrun.recording.mcap_file import OP_CHANNEL, OP_MESSAGE, OP_SCHEMA

MessageTriple = tuple[Schema | None, Channel, Message]


class Chunk(NamedTuple):
    """A verified chunk: its records, their ``(opcode, start, end)``, and the schemas and
    channels it holds (the mcap library's writer puts them in chunks)."""

    records: bytes
    spans: list[tuple[int, int, int]]
    schemas: list[Schema]
    channels: list[Channel]


def bound_ns(time_s: float | None, what: str) -> int | None:
    """A time bound in s as ns, clamped to the range log times can have (-1 .. 2**64).

    Raises:
        RecordingError: the bound is NaN.
    """
    if time_s is None:
        return None
    if math.isnan(time_s):
        raise RecordingError(f"the {what} time to read is NaN; give a number of seconds")
    return round(max(-1.0, min(float(time_s) * 1e9, 2.0**64)))


def default_channels() -> tuple[dict[int, Schema], dict[int, Channel]]:
    """The schemas/channels :class:`~flowrun.recording.McapRecorder` always registers first
    (vehicles = 1, stats = 2): used when damage hid a flowrun log's own records."""
    data = schema.schema_data()
    schemas = {
        1: Schema(id=1, name=schema.VEHICLES_TYPE, encoding=schema.ENCODING, data=data),
        2: Schema(id=2, name=schema.STATS_TYPE, encoding=schema.ENCODING, data=data),
    }
    channels = {
        cid: Channel(
            id=cid, schema_id=cid, topic=topic, message_encoding=schema.ENCODING, metadata={}
        )
        for cid, topic in ((1, schema.VEHICLES_TOPIC), (2, schema.STATS_TOPIC))
    }
    return schemas, channels


def load_chunk(f: IO[bytes], ref: mcap_records.ChunkRef, file_bytes: int) -> Chunk | Exception:
    """Read, decompress, check and split a chunk; the error instead if it is damaged."""
    try:
        records = mcap_records.chunk_records(f, ref, file_bytes)
        spans = mcap_records.split_records(records)
        schemas = [mcap_records.parse_schema(records[a:b]) for op, a, b in spans if op == OP_SCHEMA]
        channels = [
            mcap_records.parse_channel(records[a:b]) for op, a, b in spans if op == OP_CHANNEL
        ]
        return Chunk(records, spans, schemas, channels)
    except (mcap_records.BadRecord, OSError, MemoryError) as err:
        return err


def overlapping(
    refs: list[mcap_records.ChunkRef],
    lost: set[int],
    start_ns: int | None,
    end_ns: int | None,
) -> list[mcap_records.ChunkRef]:
    """The chunks not already lost that may hold times in ``start_ns``-``end_ns`` (a chunk
    whose times are not trusted is always kept)."""
    return [
        ref
        for ref in refs
        if ref.offset not in lost
        and not (
            ref.times_trusted
            and (
                (start_ns is not None and ref.end_ns < start_ns)
                or (end_ns is not None and ref.start_ns > end_ns)
            )
        )
    ]


def on_topics(channels: Mapping[int, Channel], topics: set[str] | None) -> dict[int, Channel]:
    """The channels whose topic is in ``topics`` (all of them for ``None``)."""
    return {cid: ch for cid, ch in channels.items() if topics is None or ch.topic in topics}


def chunk_messages(
    chunk: Chunk,
    keep: Mapping[int, Channel],
    schemas: Mapping[int, Schema],
    start_ns: int | None,
    end_ns: int | None,
) -> Iterator[MessageTriple]:
    """The chunk's messages on the ``keep`` channels with log times in ``start_ns``-``end_ns``
    (inclusive), in record order, as ``(schema, channel, message)``."""
    unpack, head = mcap_records.message_fields, mcap_records.MESSAGE_HEAD
    records = chunk.records
    for opcode, start, end in chunk.spans:
        if opcode != OP_MESSAGE:
            continue
        channel_id, sequence, log_time, publish_time = unpack(records, start)
        channel = keep.get(channel_id)
        if channel is None:
            continue
        if (start_ns is not None and log_time < start_ns) or (
            end_ns is not None and log_time > end_ns
        ):
            continue
        msg = Message(
            channel_id=channel_id,
            sequence=sequence,
            log_time=log_time,
            publish_time=publish_time,
            data=records[start + head : end],
        )
        yield schemas.get(channel.schema_id), channel, msg
