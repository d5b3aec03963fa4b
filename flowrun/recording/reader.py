"""Read flowrun MCAP logs back, including logs cut short by a crash.

An intact log (footer + summary) is read through the mcap library's index: a time range
only reads the chunks that overlap it. A log without a usable footer is *salvaged*: its
records are scanned from the start with the library's :class:`~mcap.stream_reader.StreamReader`
up to the first damaged record, and everything before the damage is readable.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from mcap.records import Attachment, Channel, Chunk, Footer, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk

from flowrun.errors import RecordingError
from flowrun.recording import schema
from flowrun.recording.frames import SignalFrame, StepStats, VehicleFrame
from flowrun.recording.signals import decode_signals
from flowrun.recording.writer import METADATA_NAME, to_ns

log = logging.getLogger(__name__)

MCAP_MAGIC = b"\x89MCAP0\r\n"

MessageTriple = tuple[Schema | None, Channel, Message]


@dataclass(frozen=True)
class _ChunkRef:
    offset: int
    start_ns: int
    end_ns: int


@dataclass
class _Scan:
    """What a linear scan of a log without a usable summary found."""

    chunks: list[_ChunkRef] = field(default_factory=list)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    good_bytes: int = 0
    complete: bool = False
    damage: str = ""


def _mib(n: int) -> str:
    if n < 2**20:
        return f"{n / 1024:.1f} KiB"
    return f"{n / 2**20:.1f} MiB"


class McapLog:
    """A flowrun log opened for reading (use :func:`open_log`).

    Attributes:
        path: the file.
        metadata: the ``flowrun`` metadata record (versions, seed, resolved config, ...).
        all_metadata: every metadata record, by name.
        attachments: attachment name -> bytes (e.g. ``config.yaml``, ``network.net.xml``).
        salvaged: whether the file was damaged/unfinished and read only up to the damage.
        recovered_bytes: bytes of the file that could be used (the whole size when intact).
        file_bytes: size of the file.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.file_bytes = path.stat().st_size
        self.salvaged = False
        self.recovered_bytes = self.file_bytes
        self.all_metadata: dict[str, dict[str, str]] = {}
        self.attachments: dict[str, bytes] = {}
        self._schemas: dict[int, Schema] = {}
        self._channels: dict[int, Channel] = {}
        self._scan: _Scan | None = None
        self._frame_count: int | None = None
        self._time_range_ns: tuple[int, int] | None = None
        if not self._open_indexed():
            self._open_scanned()
        self._check_topics()

    # -- opening ---------------------------------------------------------------------------
    def _open_indexed(self) -> bool:
        try:
            with open(self.path, "rb") as f:
                f.seek(-len(MCAP_MAGIC), os.SEEK_END)
                if f.read() != MCAP_MAGIC:  # cut short: the footer cannot be trusted
                    return False
                f.seek(0)
                reader = make_reader(f)
                summary = reader.get_summary()
                if summary is None or not summary.chunk_indexes:
                    return False
                self.all_metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
                self.attachments = {a.name: bytes(a.data) for a in reader.iter_attachments()}
        except Exception as err:  # no footer, truncated summary, ...: fall back to a scan
            log.debug("%s: index unusable (%s); scanning", self.path, err)
            return False
        self._schemas = dict(summary.schemas)
        self._channels = dict(summary.channels)
        stats = summary.statistics
        if stats is not None:
            self._time_range_ns = (stats.message_start_time, stats.message_end_time)
            vehicles = self._channel_id(schema.VEHICLES_TOPIC)
            if vehicles is not None:
                self._frame_count = stats.channel_message_counts.get(vehicles, 0)
        return True

    def _open_scanned(self) -> None:
        scan = _Scan()
        with open(self.path, "rb") as f:
            records = StreamReader(
                f, emit_chunks=True, record_size_limit=max(self.file_bytes, 1)
            ).records
            scan.good_bytes = 0
            try:
                for record in records:
                    end = f.tell()
                    if isinstance(record, Chunk):
                        scan.chunks.append(
                            _ChunkRef(
                                scan.good_bytes, record.message_start_time, record.message_end_time
                            )
                        )
                    elif isinstance(record, Metadata):
                        scan.metadata[record.name] = dict(record.metadata)
                    elif isinstance(record, Attachment):
                        scan.attachments[record.name] = bytes(record.data)
                    elif isinstance(record, Schema):
                        scan.schemas[record.id] = record
                    elif isinstance(record, Channel):
                        scan.channels[record.id] = record
                    elif isinstance(record, Footer):
                        scan.complete = True
                    scan.good_bytes = end
            except Exception as err:  # the damage: stop here, keep what came before
                scan.damage = f"{type(err).__name__}: {err}" if str(err) else type(err).__name__
            if scan.good_bytes == 0 and scan.damage:
                raise RecordingError(
                    f"{self.path} is not a readable MCAP file ({scan.damage}); expected a "
                    "log written by flowrun"
                )
            # Logs written by the mcap library keep schemas/channels inside the chunks (flowrun
            # writes them before the first chunk): read them from the first intact chunk(s).
            for ref in scan.chunks:
                try:
                    records_in = self._chunk_records(f, ref)
                except Exception:
                    break
                for rec in records_in:
                    if isinstance(rec, Schema):
                        scan.schemas[rec.id] = rec
                    elif isinstance(rec, Channel):
                        scan.channels[rec.id] = rec
                if any(c.topic == schema.VEHICLES_TOPIC for c in scan.channels.values()):
                    break
        self._scan = scan
        self.all_metadata = scan.metadata
        self.attachments = scan.attachments
        self._schemas = scan.schemas
        self._channels = scan.channels
        if scan.chunks:
            self._time_range_ns = (
                min(c.start_ns for c in scan.chunks),
                max(c.end_ns for c in scan.chunks),
            )
        if not scan.complete or scan.damage:
            self.salvaged = True
            self.recovered_bytes = scan.good_bytes
            span = self.time_range
            upto = f", simulation time {span[0]:.1f}-{span[1]:.1f} s" if span else ""
            log.warning(
                "%s is damaged or was not closed (%s at byte %d); salvaged %s of %s (%.1f%%) "
                "in %d chunks%s",
                self.path,
                scan.damage or "no footer",
                scan.good_bytes,
                _mib(scan.good_bytes),
                _mib(self.file_bytes),
                100.0 * scan.good_bytes / max(self.file_bytes, 1),
                len(scan.chunks),
                upto,
            )

    def _check_topics(self) -> None:
        channel = self._channel_id(schema.VEHICLES_TOPIC)
        if channel is None:
            topics = sorted({c.topic for c in self._channels.values()})
            found = ", ".join(topics) if topics else "no topics"
            damaged = " before the damage" if self.salvaged else ""
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

    def _channel_id(self, topic: str) -> int | None:
        for cid, channel in self._channels.items():
            if channel.topic == topic:
                return cid
        return None

    @staticmethod
    def _chunk_records(f: Any, ref: _ChunkRef) -> list[Any]:
        f.seek(ref.offset)
        chunk = next(StreamReader(f, skip_magic=True, emit_chunks=True).records)
        if not isinstance(chunk, Chunk):
            raise RecordingError(f"expected a chunk at byte {ref.offset}")
        return breakup_chunk(chunk, validate_crc=True)

    # -- public properties -----------------------------------------------------------------
    @property
    def metadata(self) -> dict[str, str]:
        """The ``flowrun`` metadata record (empty if the writer stored none)."""
        return self.all_metadata.get(METADATA_NAME, {})

    @property
    def time_range(self) -> tuple[float, float] | None:
        """First and last logged simulation time, s (``None`` for an empty log)."""
        if self._time_range_ns is None:
            return None
        return self._time_range_ns[0] / 1e9, self._time_range_ns[1] / 1e9

    @property
    def frame_count(self) -> int | None:
        """Number of logged steps when the index says so (``None`` for salvaged logs)."""
        return self._frame_count

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
        inclusive. Intact logs read only the chunks that overlap the range."""
        start_ns = None if start_s is None else to_ns(start_s)
        end_ns = None if end_s is None else to_ns(end_s)
        wanted = None if topics is None else set(topics)
        if self._scan is None:
            yield from self._indexed_messages(wanted, start_ns, end_ns)
        else:
            yield from self._scanned_messages(self._scan, wanted, start_ns, end_ns)

    def _indexed_messages(
        self, topics: set[str] | None, start_ns: int | None, end_ns: int | None
    ) -> Iterator[MessageTriple]:
        if start_ns is not None and end_ns is not None and end_ns < start_ns:
            return
        with open(self.path, "rb") as f:
            reader = make_reader(f)
            yield from reader.iter_messages(
                topics=None if topics is None else sorted(topics),
                starting_at=start_ns,
                ending_at=end_ns,
                # log-time order keeps decoding lazy: chunks are read one at a time (the
                # insert-order queue would decompress every chunk before yielding).
                log_time_order=True,
            )

    def _scanned_messages(
        self, scan: _Scan, topics: set[str] | None, start_ns: int | None, end_ns: int | None
    ) -> Iterator[MessageTriple]:
        with open(self.path, "rb") as f:
            for ref in scan.chunks:
                if (start_ns is not None and ref.end_ns < start_ns) or (
                    end_ns is not None and ref.start_ns > end_ns
                ):
                    continue
                try:
                    records = self._chunk_records(f, ref)
                except Exception as err:
                    log.warning(
                        "%s: chunk at byte %d is damaged (%s); stopping there",
                        self.path,
                        ref.offset,
                        err,
                    )
                    return
                for rec in records:
                    if isinstance(rec, Schema):
                        self._schemas[rec.id] = rec
                    elif isinstance(rec, Channel):
                        self._channels[rec.id] = rec
                    elif isinstance(rec, Message):
                        channel = self._channels.get(rec.channel_id)
                        if channel is None or (topics is not None and channel.topic not in topics):
                            continue
                        if (start_ns is not None and rec.log_time < start_ns) or (
                            end_ns is not None and rec.log_time > end_ns
                        ):
                            continue
                        yield self._schemas.get(channel.schema_id), channel, rec

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


def open_log(path: str | os.PathLike[str]) -> McapLog:
    """Open a flowrun MCAP log; a damaged/unfinished one is salvaged with a warning.

    Raises:
        RecordingError: the file is missing, is not MCAP, or holds no flowrun vehicle topic.
    """
    p = Path(path)
    if not p.is_file():
        raise RecordingError(
            f"{p}: no such file; expected an MCAP log (runs/<config>/<run>/*.mcap)"
        )
    with open(p, "rb") as f:
        head = f.read(len(MCAP_MAGIC))
    if head != MCAP_MAGIC:
        raise RecordingError(
            f"{p} is not an MCAP file (it does not start with the MCAP magic bytes); "
            "expected a .mcap log written by flowrun"
        )
    return McapLog(p)
