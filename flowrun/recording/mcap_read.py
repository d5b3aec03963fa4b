"""Checked low-level reading of MCAP files: every length is bounds-checked, every CRC the
format carries is verified, and damage is skipped over instead of ending the read.

Written from the MCAP specification (https://mcap.dev/spec). How a file is opened:

1. The footer (last 37 bytes before the closing magic) points at the summary section; the
   summary CRC (over the summary, the summary offsets and the footer up to the CRC) is
   checked, and the summary's chunk, metadata and attachment indexes are used. Metadata
   records are re-read and checked (their ``flowrun_crc32`` entry, see
   :func:`~flowrun.recording.mcap_file.metadata_crc`); attachments by their own CRC.
2. Without a usable footer/summary, the data section is scanned record by record. A record
   whose opcode or length cannot be right ends the walk there; the scan then looks forward
   for the next chunk (its header's ``zstd`` compression field is a 8-byte pattern, and the
   header's sizes must agree) and carries on, so one bad byte costs one chunk, not the rest.

Chunks are read later, record by record, by :func:`~flowrun.recording.mcap_records.chunk_records`
(size-capped decompression, ``uncompressed_crc`` checked).
"""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass, field
from typing import IO

from mcap.records import Channel, Schema

from flowrun.recording.damage import DamageReport, Loss
from flowrun.recording.mcap_file import (
    MAGIC,
    OP_ATTACHMENT,
    OP_ATTACHMENT_INDEX,
    OP_CHANNEL,
    OP_CHUNK,
    OP_CHUNK_INDEX,
    OP_DATA_END,
    OP_FOOTER,
    OP_HEADER,
    OP_MESSAGE_INDEX,
    OP_METADATA,
    OP_METADATA_INDEX,
    OP_SCHEMA,
    OP_STATISTICS,
)
from flowrun.recording.mcap_records import (
    CHUNK_FIXED,
    HEAD,
    U16,
    U32,
    BadRecord,
    ChunkRef,
    CrcMismatch,
    Cursor,
    done,
    parse_attachment,
    parse_channel,
    parse_chunk_header,
    parse_metadata,
    parse_schema,
    read_at,
)


@dataclass
class Structure:
    """What opening a file found (before any chunk is decompressed)."""

    size: int
    profile: str = ""
    library: str = ""
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    chunks: list[ChunkRef] = field(default_factory=list)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)
    message_counts: dict[int, int] | None = None
    indexed: bool = False
    good_bytes: int = 0
    summary_start: int = 0
    damage: DamageReport = field(default_factory=DamageReport)


def check_data_section(f: IO[bytes], st: Structure) -> bool | None:
    """Check the Data End record's CRC of the whole data section (magic to Data End).

    Returns ``None`` when there is none to check (no summary, or a CRC of 0: "not
    available", as flowrun's writer and the mcap library by default write it).
    """
    at = st.summary_start - 13  # Data End: opcode, length 4, CRC, right before the summary
    if not st.indexed or at < len(MAGIC):
        return None
    opcode, length, crc = struct.unpack("<BQI", read_at(f, at, 13))
    if opcode != OP_DATA_END or length != 4 or crc == 0:
        return None
    value, pos = 0, 0
    f.seek(0)
    while pos < at:
        block = f.read(min(8 << 20, at - pos))
        if not block:
            return False
        value = zlib.crc32(block, value)
        pos += len(block)
    return value == crc


_FOOTER = struct.Struct("<BQQQI")
_KNOWN_OPS = frozenset(range(OP_HEADER, OP_DATA_END + 1))
_SMALL_OPS = frozenset((OP_HEADER, OP_SCHEMA, OP_CHANNEL, OP_METADATA, OP_ATTACHMENT))
_ZSTD_FIELD = b"\x04\x00\x00\x00zstd"  # a chunk header's compression string
_ZSTD_AT = HEAD.size + CHUNK_FIXED.size  # where it stands in a chunk record


# -- opening -------------------------------------------------------------------------------
def read_structure(f: IO[bytes], size: int) -> Structure:
    """Everything but the chunks' contents: from the summary if it is intact, else by a scan."""
    st = Structure(size=size)
    reason = _from_summary(f, st)
    if reason is None:
        st.indexed, st.good_bytes = True, size
        return st
    st.schemas, st.channels, st.chunks = {}, {}, []
    st.metadata, st.attachments, st.message_counts = {}, {}, None
    if reason != "no footer":
        st.damage.add(Loss("index", size, f"{reason}; the data section was scanned instead"))
    _scan(f, st)
    _check_time_order(st.chunks)
    return st


def _check_time_order(chunks: list[ChunkRef]) -> None:
    """Distrust the time fields of scanned chunk headers that are out of order (flowrun
    writes chunks in time order), so a window read never skips a chunk because of them."""
    for i, ref in enumerate(chunks):
        lo = chunks[i - 1].end_ns if i else 0
        hi = chunks[i + 1].start_ns if i + 1 < len(chunks) else 1 << 64
        ref.times_trusted = lo <= ref.start_ns <= ref.end_ns <= hi


def _from_summary(f: IO[bytes], st: Structure) -> str | None:
    """Fill ``st`` from the summary; returns why it cannot be used (``None``: it was)."""
    size = st.size
    footer_at = size - len(MAGIC) - _FOOTER.size
    if footer_at < len(MAGIC) or read_at(f, size - len(MAGIC), len(MAGIC)) != MAGIC:
        return "no footer"
    opcode, length, summary_start, _, crc = _FOOTER.unpack(read_at(f, footer_at, _FOOTER.size))
    if opcode != OP_FOOTER or length != 20 or not len(MAGIC) < summary_start <= footer_at:
        return "footer damaged"
    st.summary_start = summary_start
    blob = read_at(f, summary_start, footer_at + _FOOTER.size - 4 - summary_start)
    if crc and zlib.crc32(blob) != crc:
        return "summary CRC mismatch"
    cur = Cursor(blob, 0, footer_at - summary_start)
    meta_index: list[tuple[int, int, str]] = []
    attach_index: list[tuple[int, int, str]] = []
    try:
        while cur.pos < cur.end:
            opcode, length = cur.unpack(HEAD)
            content = cur.take(length)
            body = Cursor(content)
            if opcode == OP_SCHEMA:
                sch = parse_schema(content)
                st.schemas[sch.id] = sch
            elif opcode == OP_CHANNEL:
                ch = parse_channel(content)
                st.channels[ch.id] = ch
            elif opcode == OP_STATISTICS:
                body.take(8 + 2 + 4 * 4 + 16)
                st.message_counts = body.int_map()
            elif opcode == OP_CHUNK_INDEX:
                start, end, offset, chunk_length = body.unpack(struct.Struct("<QQQQ"))
                indexes = body.int_map()
                st.chunks.append(ChunkRef(offset, chunk_length, start, end, True, indexes))
            elif opcode == OP_METADATA_INDEX:
                offset, rec_length = body.u64(), body.u64()
                meta_index.append((offset, rec_length, body.string()))
            elif opcode == OP_ATTACHMENT_INDEX:
                offset, rec_length = body.u64(), body.u64()
                body.take(24)
                attach_index.append((offset, rec_length, body.string()))
    except BadRecord as err:
        return f"summary unreadable ({err})"
    for offset, rec_length, name in meta_index:
        _load_side_record(f, st, OP_METADATA, offset, rec_length, name)
    for offset, rec_length, name in attach_index:
        _load_side_record(f, st, OP_ATTACHMENT, offset, rec_length, name)
    st.chunks.sort(key=lambda c: (c.start_ns, c.offset))
    return None


def _load_side_record(
    f: IO[bytes], st: Structure, opcode: int, offset: int, length: int, name: str
) -> None:
    """Read the metadata/attachment record an index points at; a bad one becomes a Loss."""
    part = "metadata" if opcode == OP_METADATA else "attachment"
    try:
        if offset + length > st.size or length < 9:
            raise BadRecord("the index points past the end of the file")
        rec = read_at(f, offset, length)
        op, content_length = HEAD.unpack_from(rec)
        if op != opcode or content_length != length - 9:
            raise BadRecord("record header damaged")
        _add_side_record(st, opcode, rec[9:], offset)
    except BadRecord as err:
        st.damage.add(Loss(part, offset, str(err), name=name))


def _add_side_record(st: Structure, opcode: int, content: bytes, offset: int) -> None:
    if opcode == OP_METADATA:
        name, entries, ok = parse_metadata(content)
        if ok is False:
            raise CrcMismatch("metadata CRC mismatch")
        st.metadata[name] = entries
    else:
        name, data = parse_attachment(content)
        st.attachments[name] = data


def _scan(f: IO[bytes], st: Structure) -> None:
    """Walk the data section; skip damage forward to the next chunk."""
    size, pos = st.size, len(MAGIC)
    last_chunk: ChunkRef | None = None
    while pos < size:
        head = read_at(f, pos, 9)
        if len(head) < 9:
            st.damage.add(Loss("tail", pos, "the file ends inside a record", frames=None))
            break
        opcode, length = HEAD.unpack(head)
        end = pos + 9 + length
        if opcode == OP_CHUNK and end > size:
            _lost_tail(f, st, pos)
            break
        well_formed = opcode in _KNOWN_OPS and end <= size
        if well_formed and opcode == OP_CHUNK:
            try:
                hdr = parse_chunk_header(read_at(f, pos, 128), pos, size)
            except BadRecord:
                well_formed = False
            else:
                last_chunk = ChunkRef(pos, hdr.length, hdr.start_ns, hdr.end_ns, False)
                st.chunks.append(last_chunk)
        elif well_formed and opcode == OP_MESSAGE_INDEX:
            well_formed = _well_formed_index(f, pos, length)
            if well_formed and last_chunk is not None:
                channel = U16.unpack(read_at(f, pos + 9, 2))[0]
                last_chunk.message_indexes.setdefault(channel, pos)
        elif well_formed and opcode in (OP_FOOTER, OP_DATA_END):
            st.good_bytes = end
            if opcode == OP_DATA_END and not any(x.part == "index" for x in st.damage.losses):
                st.damage.add(Loss("index", pos, "the summary after Data End is unusable"))
            return
        elif well_formed and opcode in _SMALL_OPS:
            well_formed = _scan_small_record(f, st, opcode, pos, length)
        if not well_formed:
            after = _resync(f, pos + 1, size)
            if after is None:
                lo = last_chunk.end_ns / 1e9 if last_chunk else None
                why = f"unreadable record (opcode 0x{opcode:02x}); no readable chunk after it"
                st.damage.add(Loss("tail", pos, why, lo, None))
                break
            _skipped(st, pos, after, last_chunk, opcode)
            pos = after[0]
            continue
        st.good_bytes = pos = end
    if not any(x.part in ("tail", "index") for x in st.damage.losses):
        st.damage.add(Loss("unfinished", size, "no footer: the log was not closed", frames=0))


def _scan_small_record(f: IO[bytes], st: Structure, opcode: int, pos: int, length: int) -> bool:
    """Read a non-chunk record met by the scan; returns whether its length can be trusted
    (a bad CRC in a well-formed record costs that record only)."""
    part = {OP_METADATA: "metadata", OP_ATTACHMENT: "attachment"}.get(opcode, "record")
    try:
        content = read_at(f, pos + 9, length)
        cur = Cursor(content)
        if opcode == OP_HEADER:
            st.profile, st.library = cur.string(), cur.string()
            done(cur)
        elif opcode == OP_SCHEMA:
            sch = parse_schema(content)
            st.schemas[sch.id] = sch
        elif opcode == OP_CHANNEL:
            ch = parse_channel(content)
            st.channels[ch.id] = ch
        else:
            _add_side_record(st, opcode, content, pos)
    except CrcMismatch as err:
        st.damage.add(Loss(part, pos, str(err)))
        return True
    except BadRecord as err:
        st.damage.add(Loss(part, pos, str(err)))
        return False
    return True


def _well_formed_index(f: IO[bytes], pos: int, length: int) -> bool:
    """Whether the Message Index record at ``pos`` has a length its entries fill."""
    if length < 6:
        return False
    nbytes = U32.unpack(read_at(f, pos + 11, 4))[0]
    return bool(nbytes + 6 == length and nbytes % 16 == 0)


def _skipped(
    st: Structure, pos: int, after: tuple[int, int], last_chunk: ChunkRef | None, opcode: int
) -> None:
    """Report the bytes from a damaged record at ``pos`` to the next chunk."""
    why = f"unreadable record (opcode 0x{opcode:02x}); skipped {after[0] - pos} bytes"
    if last_chunk is None:  # before the first chunk: schemas, channels, metadata, no data
        st.damage.add(Loss("records", pos, f"{why} to the first chunk", frames=0))
    else:
        lo, hi = last_chunk.end_ns / 1e9, after[1] / 1e9
        st.damage.add(Loss("chunk", pos, f"{why}; data between them may be lost", lo, hi))


def _lost_tail(f: IO[bytes], st: Structure, pos: int) -> None:
    """The file ends inside the chunk at ``pos``: report what its header says it held."""
    head = read_at(f, pos, 128)
    start = end = None
    if len(head) >= _ZSTD_AT:
        start_ns, end_ns = struct.unpack_from("<QQ", head, 9)
        if end_ns >= start_ns:
            start, end = start_ns / 1e9, end_ns / 1e9
    st.damage.add(Loss("tail", pos, "the file ends inside this chunk (cut short)", start, end))


def _resync(f: IO[bytes], pos: int, size: int) -> tuple[int, int] | None:
    """``(offset, start_ns)`` of the first well-formed chunk at or after ``pos``."""
    block, origin = 4 << 20, pos
    while pos < size:
        buf = read_at(f, pos, block + len(_ZSTD_FIELD))
        hit = buf.find(_ZSTD_FIELD)
        while hit >= 0:
            at = pos + hit - _ZSTD_AT
            if at >= origin:
                try:
                    hdr = parse_chunk_header(read_at(f, at, 128), at, size)
                except BadRecord:
                    pass
                else:
                    if hdr.start_ns <= hdr.end_ns:
                        return at, hdr.start_ns
            hit = buf.find(_ZSTD_FIELD, hit + 1)
        pos += block
    return None
