"""Read flowrun MCAP logs back, checking every CRC, and salvage damaged or unfinished ones.

An intact log (footer + CRC-checked summary) is read through its chunk index: a time range
only reads the chunks that overlap it. A log without a usable summary is scanned record by
record (:mod:`flowrun.recording.mcap_read`), skipping damage forward to the next chunk. Each
chunk's CRC is checked when it is decompressed: a bad chunk is skipped, the others are read,
and :attr:`McapLog.damage` says what was lost (a warning is logged for each damaged part).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import IO, Any

from mcap.records import Channel, Schema

from flowrun.errors import RecordingError
from flowrun.recording import mcap_read, mcap_records, schema
from flowrun.recording.chunks import (
    Chunk,
    MessageTriple,
    bound_ns,
    chunk_messages,
    default_channels,
    load_chunk,
    on_topics,
    overlapping,
)
from flowrun.recording.damage import DamageReport, Loss
from flowrun.recording.frames import SignalFrame, StepStats, VehicleFrame
from flowrun.recording.signals import decode_signals
from flowrun.recording.writer import METADATA_NAME, PROFILE

log = logging.getLogger(__name__)

MCAP_MAGIC = b"\x89MCAP0\r\n"


def _mib(n: int) -> str:
    if n < 2**20:
        return f"{n / 1024:.1f} KiB"
    return f"{n / 2**20:.1f} MiB"


class McapLog:
    """A flowrun log opened for reading (use :func:`open_log`).

    Attributes:
        path: the file.
        metadata: the ``flowrun`` metadata record (versions, seed, resolved config, ...).
        all_metadata: every metadata record, by name (a damaged record is left out and
            reported in :attr:`damage`).
        attachments: attachment name -> bytes (e.g. ``config.yaml``, ``network.net.xml``);
            a damaged attachment is left out and reported.
        damage: what is damaged or lost; grows while chunks are read (each chunk's CRC is
            checked when it is first decompressed), complete after a full read.
        file_bytes: size of the file.
    """

    def __init__(self, path: Path, damaged_magic: Loss | None = None) -> None:
        self.path = path
        self.file_bytes = path.stat().st_size
        try:
            with open(path, "rb") as f:
                st = mcap_read.read_structure(f, self.file_bytes)
        except OSError as err:
            raise RecordingError(f"cannot read {path}: {err}") from err
        self._st = st
        self.damage: DamageReport = st.damage
        if damaged_magic is not None:
            self.damage.losses.insert(0, damaged_magic)
        self.all_metadata = st.metadata
        self.attachments = st.attachments
        self._schemas: dict[int, Schema] = dict(st.schemas)
        self._channels: dict[int, Channel] = dict(st.channels)
        self._lost_offsets: set[int] = set()
        if not st.chunks and st.damage and not st.indexed:
            raise RecordingError(
                f"{path} holds no readable data ({'; '.join(st.damage.describe())}); "
                "expected a log written by flowrun"
            )
        self._find_channels()
        self._check_topics()
        if self.damage:
            span = self.time_range
            upto = f", simulation time {span[0]:.1f}-{span[1]:.1f} s" if span else ""
            log.warning(
                "%s is damaged or was not closed; salvaged %s of %s in %d chunks%s: %s",
                self.path,
                _mib(self.recovered_bytes),
                _mib(self.file_bytes),
                len(st.chunks),
                upto,
                "; ".join(self.damage.describe()),
            )

    def _find_channels(self) -> None:
        """Logs written by the mcap library keep schemas/channels inside the chunks: read
        them from the first intact chunk(s); a flowrun log whose own records were damaged
        gets the recorder's fixed ones."""
        if self._vehicles_ok() or not self._st.chunks:
            return
        with open(self.path, "rb") as f:
            for ref in self._st.chunks[:8]:
                chunk = self._chunk(f, ref)
                if chunk is None:
                    continue
                self._learn(chunk)
                if self._vehicles_ok():
                    return
        # McapRecorder (library "flowrun") registers vehicles = 1 and stats = 2 first
        recorder = (self._st.profile, self._st.library) == (PROFILE, "flowrun")
        header_lost = self._st.profile == "" and any(
            x.part == "records" for x in self.damage.losses
        )
        if (recorder or header_lost) and self.damage:
            schemas, channels = default_channels()
            self._schemas.update(schemas)
            self._channels.update(channels)
            self.damage.add(
                Loss(
                    "channels",
                    0,
                    "the channel records are unreadable; read with flowrun's "
                    "standard channels (vehicles = 1, stats = 2)",
                )
            )

    def _vehicles_ok(self) -> bool:
        """Whether the vehicles channel is known, with its schema."""
        channel = self._channels.get(self._channel_id(schema.VEHICLES_TOPIC) or -1)
        sch = None if channel is None else self._schemas.get(channel.schema_id)
        return sch is not None and sch.name == schema.VEHICLES_TYPE

    def _check_topics(self) -> None:
        channel = self._channel_id(schema.VEHICLES_TOPIC)
        if channel is None:
            topics = sorted({c.topic for c in self._channels.values()})
            found = ", ".join(topics) if topics else "no topics"
            damaged = " readable (the log is damaged)" if self.damage else ""
            raise RecordingError(
                f"{self.path} has no {schema.VEHICLES_TOPIC} topic{damaged} (found: {found}); "
                "expected a log written by flowrun baseline/train/eval"
            )
        ch = self._channels[channel]
        sch = self._schemas.get(ch.schema_id)
        expected = schema.VEHICLES_TYPE
        if ch.message_encoding != schema.ENCODING or sch is None or sch.name != expected:
            raise RecordingError(
                f"{self.path}: {schema.VEHICLES_TOPIC} is encoded as {ch.message_encoding!r} "
                f"with schema {sch.name if sch else None!r}; this flowrun reads "
                f"{schema.ENCODING!r} {schema.VEHICLES_TYPE!r}"
            )

    def _learn(self, chunk: Chunk) -> None:
        """Keep the schemas and channels a chunk carries (the summary may have lost them)."""
        for sch in chunk.schemas:
            self._schemas.setdefault(sch.id, sch)
        for ch in chunk.channels:
            self._channels.setdefault(ch.id, ch)

    def _chunk(self, f: IO[bytes], ref: mcap_records.ChunkRef) -> Chunk | None:
        """A chunk's verified records, or ``None`` (recorded in :attr:`damage`, warned once)."""
        if ref.offset in self._lost_offsets:
            return None
        return self._settle(f, ref, self._load(f, ref))

    def _load(self, f: IO[bytes], ref: mcap_records.ChunkRef) -> Chunk | Exception:
        """Read, decompress, check and split a chunk (no state changes: runs in a thread)."""
        return load_chunk(f, ref, self.file_bytes)

    def _settle(
        self, f: IO[bytes], ref: mcap_records.ChunkRef, loaded: Chunk | Exception
    ) -> Chunk | None:
        """The loaded chunk, or ``None`` after recording why it is lost."""
        if isinstance(loaded, Chunk):
            return loaded
        self._lost_offsets.add(ref.offset)
        vehicles = self._channel_id(schema.VEHICLES_TOPIC)
        frames = None
        if vehicles is not None:
            frames = mcap_records.count_messages(f, ref, vehicles, self.file_bytes)
        loss = Loss("chunk", ref.offset, str(loaded), ref.start_ns / 1e9, ref.end_ns / 1e9, frames)
        if self.damage.add(loss):
            log.warning("%s: %s; the other chunks are read", self.path, loss.describe())
        return None

    def _channel_id(self, topic: str) -> int | None:
        for cid, channel in self._channels.items():
            if channel.topic == topic:
                return cid
        return None

    # -- public properties -----------------------------------------------------------------
    @property
    def metadata(self) -> dict[str, str]:
        """The ``flowrun`` metadata record (empty if the writer stored none)."""
        return self.all_metadata.get(METADATA_NAME, {})

    @property
    def salvaged(self) -> bool:
        """Whether the log is damaged or unfinished (see :attr:`damage` for what was lost)."""
        return bool(self.damage)

    @property
    def recovered_bytes(self) -> int:
        """Bytes of the file that could be used (the whole size when intact)."""
        lost = sum(ref.length for ref in self._st.chunks if ref.offset in self._lost_offsets)
        return max(self._st.good_bytes - lost, 0)

    @property
    def time_range(self) -> tuple[float, float] | None:
        """First and last logged simulation time, s (``None`` for an empty log)."""
        chunks = [c for c in self._st.chunks if c.times_trusted] or self._st.chunks
        if not chunks:
            return None
        return min(c.start_ns for c in chunks) / 1e9, max(c.end_ns for c in chunks) / 1e9

    @property
    def frame_count(self) -> int | None:
        """Number of logged steps when the index says so (``None`` for damaged logs)."""
        counts = self._st.message_counts
        vehicles = self._channel_id(schema.VEHICLES_TOPIC)
        if counts is None or vehicles is None or self.damage:
            return None
        return counts.get(vehicles, 0)

    @property
    def topics(self) -> list[str]:
        """Topics of the log."""
        return sorted({c.topic for c in self._channels.values()})

    # -- messages --------------------------------------------------------------------------
    def messages(
        self,
        topics: Iterable[str] | None = None,
        start_s: float | None = None,
        end_s: float | None = None,
    ) -> Iterator[MessageTriple]:
        """Raw ``(schema, channel, message)`` triples in log-time order, ``start_s``-``end_s``
        inclusive, from the chunks that overlap the range. A damaged chunk is skipped (and
        added to :attr:`damage`); the others are read."""
        start_ns, end_ns = bound_ns(start_s, "start"), bound_ns(end_s, "end")
        if start_ns is not None and end_ns is not None and end_ns < start_ns:
            return
        wanted = None if topics is None else set(topics)
        refs = overlapping(self._st.chunks, self._lost_offsets, start_ns, end_ns)
        # One worker reads (with its own file handle), decompresses and CRC-checks the next
        # chunk while this one's messages are used (zstd and zlib release the GIL); nothing
        # leaves unchecked.
        with (
            open(self.path, "rb") as f,
            open(self.path, "rb") as worker_f,
            ThreadPoolExecutor(1) as pool,
        ):
            pending = pool.submit(self._load, worker_f, refs[0]) if refs else None
            for i, ref in enumerate(refs):
                assert pending is not None
                loaded = pending.result()
                if i + 1 < len(refs):
                    pending = pool.submit(self._load, worker_f, refs[i + 1])
                chunk = self._settle(f, ref, loaded)
                if chunk is None:
                    continue
                self._learn(chunk)
                keep = on_topics(self._channels, wanted)
                yield from chunk_messages(chunk, keep, self._schemas, start_ns, end_ns)

    def verify(self) -> DamageReport:
        """Read every chunk (checking its CRC) and the data section's CRC where the writer
        stored one (:meth:`check_data_section`); returns the complete :attr:`damage`."""
        for _ in self.messages(topics=()):
            pass
        self.check_data_section()
        return self.damage

    def check_data_section(self) -> None:
        """Check Data End's CRC of the data section, when the writer stored one (the mcap
        library's ``enable_data_crcs``; flowrun's writer stores 0, "not available"): a
        mismatch is added to :attr:`damage`. Reads the whole data section once."""
        with open(self.path, "rb") as f:
            ok = mcap_read.check_data_section(f, self._st)
        if ok is not False:
            return
        chunks = "some chunks are damaged" if self.damage.lost_chunks else "every chunk checked"
        loss = Loss(
            "data section",
            0,
            f"Data End's CRC of the data section does not match ({chunks}; the damage may "
            "be in a schema, channel, metadata or index record)",
        )
        if self.damage.add(loss):
            log.warning("%s: %s", self.path, loss.describe())

    def vehicle_messages(
        self, start_s: float | None = None, end_s: float | None = None
    ) -> Iterator[Any]:
        """Parsed ``flowrun.VehicleFrame`` protobuf messages (fast access to single columns:
        ``numpy.array(msg.speed)``)."""
        for _, _, message in self.messages([schema.VEHICLES_TOPIC], start_s, end_s):
            yield schema.parse_frame(message.data)

    def frames(
        self,
        start_s: float | None = None,
        end_s: float | None = None,
        vehicles: Iterable[str] | None = None,
    ) -> Iterator[VehicleFrame]:
        """Logged steps between ``start_s`` and ``end_s`` (inclusive, s).

        Args:
            start_s: first simulation time to read, s (``None``: from the start).
            end_s: last simulation time to read, s (``None``: to the end).
            vehicles: keep only these vehicle ids (``None``: all).
        """
        wanted = None if vehicles is None else set(vehicles)
        last_ids: list[str] | None = None
        keep: list[int] | None = None
        last_roster = -1
        for msg in self.vehicle_messages(start_s, end_s):
            roster = msg.roster_version
            if wanted is not None and (roster == 0 or roster != last_roster):
                last_roster = roster
                ids = list(msg.ids)
                if ids != last_ids:
                    keep = [i for i, vid in enumerate(ids) if vid in wanted]
                    last_ids = ids
            yield schema.frame_from_message(msg, keep)

    def stats(
        self, start_s: float | None = None, end_s: float | None = None
    ) -> Iterator[StepStats]:
        """Per-step aggregates between ``start_s`` and ``end_s`` (inclusive, s)."""
        for _, _, message in self.messages([schema.STATS_TOPIC], start_s, end_s):
            yield schema.decode_stats(message.data)

    @property
    def has_signals(self) -> bool:
        """Whether the log has a ``/flowrun/traffic_lights`` topic (a network with lights,
        logged by a flowrun that records them)."""
        return self._channel_id(schema.SIGNALS_TOPIC) is not None

    def signals(
        self, start_s: float | None = None, end_s: float | None = None
    ) -> Iterator[SignalFrame]:
        """Every traffic light's state per logged step between ``start_s`` and ``end_s``
        (inclusive, s); nothing for logs without lights (or written before they were logged).
        """
        if not self.has_signals:
            return
        for _, _, message in self.messages([schema.SIGNALS_TOPIC], start_s, end_s):
            yield decode_signals(message.data)


def _ends_with_magic(path: Path) -> bool:
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            if f.tell() < 2 * len(MCAP_MAGIC):
                return False
            f.seek(-len(MCAP_MAGIC), os.SEEK_END)
            return f.read() == MCAP_MAGIC
    except OSError:
        return False


def open_log(path: str | os.PathLike[str]) -> McapLog:
    """Open a flowrun MCAP log; a damaged/unfinished one is salvaged with a warning.

    Raises:
        RecordingError: the file is missing, is not MCAP, or holds no flowrun vehicle topic.
    """
    p = Path(path)
    if p.is_dir():
        raise RecordingError(f"{p} is a folder; give an MCAP log in it (e.g. {p}/run_0.mcap)")
    if not p.is_file():
        what = "not a regular file" if p.exists() else "no such file"
        raise RecordingError(f"{p}: {what}; expected an MCAP log (runs/<config>/<run>/*.mcap)")
    try:
        with open(p, "rb") as f:
            head = f.read(len(MCAP_MAGIC) + 1)
    except OSError as err:
        raise RecordingError(f"cannot read {p}: {err.strerror or err}") from None
    if head[:8] == MCAP_MAGIC:
        return McapLog(p)
    # A damaged start must not cost the log: accept 7 of 8 magic bytes followed by a Header
    # record (opcode 0x01), or a file that ends with the magic (a footer), and say so.
    same = sum(a == b for a, b in zip(head, MCAP_MAGIC, strict=False))
    if (same >= len(MCAP_MAGIC) - 1 and head[8:9] == b"\x01") or _ends_with_magic(p):
        return McapLog(p, Loss("magic", 0, "the leading magic bytes are damaged"))
    raise RecordingError(
        f"{p} is not an MCAP file (it does not start with the MCAP magic bytes); "
        "expected a .mcap log written by flowrun"
    )
