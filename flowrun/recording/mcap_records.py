"""MCAP records read with every length bounds-checked and every CRC checked: the parsers
:mod:`flowrun.recording.mcap_read` opens files with, and the chunk reader.

Written from the MCAP specification (https://mcap.dev/spec). A chunk is decompressed with its
size capped by its header, and checked against its ``uncompressed_crc``; anything that cannot
be what the writer wrote raises :class:`BadRecord` (:class:`CrcMismatch` when only a CRC
fails), which callers turn into a :class:`~flowrun.recording.damage.Loss`.
"""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass, field
from typing import IO

import zstandard
from mcap.records import Channel, Schema

from flowrun.recording.mcap_file import (
    CRC_KEY,
    OP_CHUNK,
    OP_MESSAGE,
    OP_MESSAGE_INDEX,
    metadata_crc,
)

U16 = struct.Struct("<H")
U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")
HEAD = struct.Struct("<BQ")
_MSG = struct.Struct("<HIQQ")
MESSAGE_HEAD = _MSG.size
"""Bytes of a Message record's content before its data."""
CHUNK_FIXED = struct.Struct("<QQQI")
MAX_CHUNK_BYTES = 1 << 31
"""Largest uncompressed chunk accepted (a damaged size field must not allocate more)."""


class BadRecord(Exception):
    """A record that cannot be what the writer wrote (internal; callers turn it into a
    :class:`~flowrun.recording.damage.Loss`)."""


class CrcMismatch(BadRecord):
    """A well-formed record whose content fails its CRC (its length can be trusted)."""


class Cursor:
    """Reads the spec's little-endian fields from a buffer, never past ``end``."""

    def __init__(self, buf: bytes, pos: int = 0, end: int | None = None) -> None:
        self.buf, self.pos = buf, pos
        self.end = len(buf) if end is None else end

    def take(self, n: int) -> bytes:
        if n < 0 or self.pos + n > self.end:
            raise BadRecord(f"a field of {n} bytes runs past its record")
        out = self.buf[self.pos : self.pos + n]
        self.pos += n
        return out

    def unpack(self, fmt: struct.Struct) -> tuple[int, ...]:
        return fmt.unpack(self.take(fmt.size))

    def u16(self) -> int:
        return int(self.unpack(U16)[0])

    def u32(self) -> int:
        return int(self.unpack(U32)[0])

    def u64(self) -> int:
        return int(self.unpack(_U64)[0])

    def string(self) -> str:
        try:
            return self.take(self.u32()).decode("utf-8")
        except UnicodeDecodeError as err:
            raise BadRecord(f"a string is not UTF-8 ({err.reason})") from None

    def string_map(self) -> dict[str, str]:
        n = self.u32()
        sub = Cursor(self.buf, self.pos, self.pos + n)
        self.take(n)
        out: dict[str, str] = {}
        while sub.pos < sub.end:
            k = sub.string()
            out[k] = sub.string()
        return out

    def int_map(self) -> dict[int, int]:
        n = self.u32()
        sub = Cursor(self.buf, self.pos, self.pos + n)
        self.take(n)
        out: dict[int, int] = {}
        while sub.pos < sub.end:
            k = sub.u16()
            out[k] = sub.u64()
        return out


@dataclass
class ChunkRef:
    """Where a chunk is and what the index (or its header) says it holds.

    Attributes:
        offset: byte offset of the Chunk record.
        length: record length with opcode and length field, bytes.
        start_ns: first message log time, ns.
        end_ns: last message log time, ns.
        indexed: whether the fields come from the CRC-checked summary (else from the
            chunk's own header, unchecked until the chunk is read).
        message_indexes: channel id -> offset of its Message Index record (for counting
            what a damaged chunk held).
        times_trusted: whether ``start_ns``/``end_ns`` may be used to skip the chunk when
            reading a time window (false for a scanned header out of order with its
            neighbours: its time fields, outside the chunk's CRC, may be damaged).
    """

    offset: int
    length: int
    start_ns: int
    end_ns: int
    indexed: bool
    message_indexes: dict[int, int] = field(default_factory=dict)
    times_trusted: bool = True


def read_at(f: IO[bytes], offset: int, n: int) -> bytes:
    """``n`` bytes at ``offset`` (fewer at the end of the file)."""
    f.seek(offset)
    return f.read(n)


# -- records -------------------------------------------------------------------------------
def done(cur: Cursor) -> None:
    """A scanned record's fields must fill it exactly (else its length field is damaged)."""
    if cur.pos != cur.end:
        raise BadRecord("the record's length does not match its fields")


def parse_metadata(content: bytes) -> tuple[str, dict[str, str], bool | None]:
    """A Metadata record's name and entries, and whether its ``flowrun_crc32`` entry matched
    (``None`` when it has none: written by another tool or an older flowrun)."""
    cur = Cursor(content)
    name = cur.string()
    entries = cur.string_map()
    done(cur)
    stored = entries.pop(CRC_KEY, None)
    if stored is None:
        return name, entries, None
    return name, entries, stored == f"{metadata_crc(name, entries):08x}"


def parse_attachment(content: bytes) -> tuple[str, bytes]:
    """An Attachment record's name and data; raises :class:`BadRecord` on a CRC mismatch."""
    cur = Cursor(content)
    cur.take(16)  # log and create time
    name = cur.string()
    cur.string()  # media type
    data = cur.take(cur.u64())
    fields_end = cur.pos
    crc = cur.u32()
    done(cur)
    if crc and zlib.crc32(content[:fields_end]) != crc:
        raise CrcMismatch("attachment CRC mismatch")
    return name, data


def parse_schema(content: bytes) -> Schema:
    cur = Cursor(content)
    sid = cur.u16()
    name, encoding = cur.string(), cur.string()
    data = cur.take(cur.u32())
    done(cur)
    return Schema(id=sid, name=name, encoding=encoding, data=data)


def parse_channel(content: bytes) -> Channel:
    cur = Cursor(content)
    cid, sid = cur.u16(), cur.u16()
    topic, encoding = cur.string(), cur.string()
    metadata = cur.string_map()
    done(cur)
    return Channel(id=cid, schema_id=sid, topic=topic, message_encoding=encoding, metadata=metadata)


@dataclass(frozen=True)
class ChunkHeader:
    """A Chunk record's header fields."""

    start_ns: int
    end_ns: int
    uncompressed_size: int
    crc: int
    compression: str
    data_offset: int
    data_size: int
    length: int


def parse_chunk_header(head: bytes, offset: int, size: int) -> ChunkHeader:
    """The header of the Chunk record at ``offset`` (``head``: its first bytes).

    Raises:
        BadRecord: not a chunk, or its fields disagree with each other or the file size.
    """
    cur = Cursor(head)
    opcode, length = cur.unpack(HEAD)
    if opcode != OP_CHUNK:
        raise BadRecord(f"expected a chunk record, found opcode 0x{opcode:02x}")
    if offset + HEAD.size + length > size:
        raise BadRecord(f"chunk record of {length} bytes runs past the end of the file")
    start, end, usize, crc = cur.unpack(CHUNK_FIXED)
    compression = cur.string()
    csize = cur.u64()
    if cur.pos + csize != HEAD.size + length or usize > MAX_CHUNK_BYTES:
        raise BadRecord("chunk header fields are inconsistent")
    return ChunkHeader(start, end, usize, crc, compression, offset + cur.pos, csize, length + 9)


def chunk_records(f: IO[bytes], ref: ChunkRef, size: int) -> bytes:
    """The verified, decompressed records of a chunk.

    Raises:
        BadRecord: the chunk's header, compression or CRC is wrong.
    """
    head = parse_chunk_header(read_at(f, ref.offset, 128), ref.offset, size)
    # (the header's time fields are outside the CRC and not needed: the index's are used)
    if ref.indexed and head.length != ref.length:
        raise BadRecord("chunk header disagrees with the index")
    data = read_at(f, head.data_offset, head.data_size)
    if head.compression == "zstd":
        try:
            if zstandard.frame_content_size(data) != head.uncompressed_size:
                raise BadRecord("compressed data does not match the chunk's size")
            records = zstandard.ZstdDecompressor().decompress(
                data, max_output_size=head.uncompressed_size
            )
        except zstandard.ZstdError as err:
            raise BadRecord(f"zstd: {err}") from None
    elif head.compression == "":
        records = data
    else:
        raise BadRecord(f"unknown compression {head.compression[:16]!r}")
    if len(records) != head.uncompressed_size:
        raise BadRecord("decompressed size differs from the chunk's")
    if head.crc and zlib.crc32(records) != head.crc:
        raise BadRecord("CRC mismatch")
    return records


def split_records(records: bytes) -> list[tuple[int, int, int]]:
    """``(opcode, content start, content end)`` of each record in a chunk's records."""
    out: list[tuple[int, int, int]] = []
    pos, n, head = 0, len(records), HEAD.unpack_from
    while pos < n:
        if pos + 9 > n:
            raise BadRecord("a record inside the chunk is cut short")
        opcode, length = head(records, pos)
        start = pos + 9
        pos = start + length
        if pos > n:
            raise BadRecord("a record inside the chunk runs past it")
        if opcode == OP_MESSAGE and length < MESSAGE_HEAD:
            raise BadRecord("a message inside the chunk is too short")
        out.append((opcode, start, pos))
    return out


def message_fields(records: bytes, start: int) -> tuple[int, int, int, int]:
    """``(channel id, sequence, log time, publish time)`` of the Message content at ``start``."""
    return _MSG.unpack_from(records, start)


def count_messages(f: IO[bytes], ref: ChunkRef, channel_id: int, size: int) -> int | None:
    """Messages of ``channel_id`` in a chunk, from its Message Index record (``None`` when
    it has none or it is unreadable)."""
    offset = ref.message_indexes.get(channel_id)
    if offset is None or offset + 15 > size:
        return None
    opcode, length, channel, nbytes = struct.unpack("<BQHI", read_at(f, offset, 15))
    if opcode != OP_MESSAGE_INDEX or channel != channel_id or nbytes % 16 or nbytes + 6 != length:
        return None
    return nbytes // 16
