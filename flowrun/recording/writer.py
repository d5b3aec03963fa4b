"""Write a run's per-step vehicle states to an MCAP file (zstd chunks, protobuf messages)."""

from __future__ import annotations

import logging
import os
import time
from pathlib import Path
from types import TracebackType
from typing import IO

from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import CompressionType, Writer

from flowrun.errors import RecordingError
from flowrun.recording import schema
from flowrun.recording.frames import StepStats, VehicleFrame

log = logging.getLogger(__name__)

METADATA_NAME = "flowrun"
PROFILE = "flowrun"
CHUNK_SIZE = 4 * 1024 * 1024

_MEDIA_TYPES = {
    ".yaml": "application/yaml",
    ".yml": "application/yaml",
    ".xml": "application/xml",
    ".json": "application/json",
    ".txt": "text/plain",
}


def media_type(name: str) -> str:
    """The media type stored with an attachment, guessed from its file name."""
    return _MEDIA_TYPES.get(Path(name).suffix.lower(), "application/octet-stream")


def to_ns(time_s: float) -> int:
    """Simulation time in seconds to an MCAP timestamp (ns)."""
    return round(time_s * 1e9)


ROSTER_METADATA = "flowrun_roster"


class McapRecorder:
    """Records :class:`VehicleFrame`/:class:`StepStats` pairs to one MCAP file.

    Metadata and attachments are written first, so even a file cut short by a crash carries
    them. Data is flushed as finished zstd chunks every ``flush_every_s`` seconds of wall
    time (and right after the first logged step), so a killed process leaves a file that
    :func:`flowrun.recording.open_log` salvages up to the last flush. :meth:`close` writes the
    summary and footer; it is idempotent and safe to call from a ``finally`` block.

    Args:
        path: output file; its parent directory is created.
        metadata: key/value pairs stored in the ``flowrun`` metadata record (versions, seed,
            resolved config, ...).
        attachments: file name -> content (e.g. ``config.yaml``, ``network.net.xml``).
        record_every: keep only steps whose index is a multiple of this (1 keeps all).
        flush_every_s: wall-clock seconds between forced chunk flushes (crash safety).
        chunk_size: uncompressed bytes after which a chunk is closed anyway.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        metadata: dict[str, str] | None = None,
        attachments: dict[str, bytes] | None = None,
        record_every: int = 1,
        flush_every_s: float = 2.0,
        chunk_size: int = CHUNK_SIZE,
    ) -> None:
        if record_every < 1:
            raise RecordingError(f"record_every must be >= 1, got {record_every}")
        self.path = Path(path)
        self.record_every = int(record_every)
        self.flush_every_s = float(flush_every_s)
        self.frames_written = 0
        self._roster: tuple[list[str], list[str], list[bool]] = ([], [], [])
        self._roster_version = 0
        self._closed = False
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._stream: IO[bytes] = open(self.path, "wb")  # noqa: SIM115 - closed in close()
        except OSError as err:
            raise RecordingError(f"cannot create MCAP log {self.path}: {err}") from err
        self._writer = Writer(self._stream, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        self._writer.start(profile=PROFILE, library="flowrun")
        meta = {str(k): str(v) for k, v in (metadata or {}).items()}
        self._writer.add_metadata(METADATA_NAME, meta)
        for name, data in (attachments or {}).items():
            self._writer.add_attachment(
                create_time=time.time_ns(),
                log_time=0,
                name=name,
                media_type=media_type(name),
                data=bytes(data),
            )
        schema_bytes = schema.schema_data()
        vehicles_schema = self._writer.register_schema(
            schema.VEHICLES_TYPE, SchemaEncoding.Protobuf, schema_bytes
        )
        stats_schema = self._writer.register_schema(
            schema.STATS_TYPE, SchemaEncoding.Protobuf, schema_bytes
        )
        self._vehicles = self._writer.register_channel(
            schema.VEHICLES_TOPIC, MessageEncoding.Protobuf, vehicles_schema
        )
        self._stats = self._writer.register_channel(
            schema.STATS_TOPIC, MessageEncoding.Protobuf, stats_schema
        )
        self._last_flush = time.monotonic()

    def write(self, frame: VehicleFrame, stats: StepStats) -> bool:
        """Log one step unless thinned out by ``record_every``.

        Returns:
            whether the step was written.
        """
        if self._closed:
            raise RecordingError(f"MCAP log {self.path} is already closed")
        if frame.step % self.record_every:
            return False
        stamp = to_ns(frame.time)
        seq = frame.step & 0xFFFFFFFF
        is_rl = frame.is_rl.tolist()
        ids, types, rl = self._roster
        if frame.ids != ids or frame.types != types or is_rl != rl:
            self._roster = (list(frame.ids), list(frame.types), is_rl)
            self._roster_version = self._roster_version % 0xFFFFFFFF + 1
        writer = self._writer
        # Stats first: if a crash cuts between the two, every salvaged frame has its stats.
        writer.add_message(self._stats, stamp, schema.encode_stats(stats), stamp, seq)
        writer.add_message(
            self._vehicles, stamp, schema.encode_frame(frame, self._roster_version), stamp, seq
        )
        self.frames_written += 1
        now = time.monotonic()
        if self.frames_written == 1 or now - self._last_flush >= self.flush_every_s:
            self.flush()
            self._last_flush = now
        return True

    def flush(self) -> None:
        """End the current chunk and push everything written so far to the OS."""
        if not self._closed:
            self._writer.flush()

    def close(self) -> None:
        """Write the summary and footer and close the file (idempotent)."""
        if self._closed:
            return
        self._closed = True
        try:
            # How many different rosters (ids/types/RL flags) the frames had: with one, a
            # reader may take the roster from the first frame and skip decoding the rest.
            self._writer.add_metadata(ROSTER_METADATA, {"rosters": str(self._roster_version)})
            self._writer.finish()
        finally:
            self._stream.close()
        log.debug("wrote %d frames to %s", self.frames_written, self.path)

    finish = close

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run."""
        return self._closed

    def __enter__(self) -> McapRecorder:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
