"""Write a run's per-step vehicle states to an MCAP file (zstd chunks, protobuf messages)."""

from __future__ import annotations

import logging
import os
import time
from dataclasses import replace
from pathlib import Path
from types import TracebackType
from typing import IO, Any

import numpy as np

from flowrun.errors import RecordingError
from flowrun.recording import schema
from flowrun.recording.frames import SignalFrame, StepStats, VehicleFrame
from flowrun.recording.mcap_file import CHUNK_SIZE, McapWriter
from flowrun.recording.scene import SCENE_TOPIC, SCENE_TYPE, SceneEncoder
from flowrun.recording.scene import schema_data as scene_schema_data
from flowrun.recording.signals import SignalEncoder

log = logging.getLogger(__name__)

METADATA_NAME = "flowrun"
PROFILE = "flowrun"

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
    """Records :class:`VehicleFrame`/:class:`StepStats` pairs to one MCAP file (and the
    :class:`SignalFrame` of each step on networks with traffic lights: the
    ``/flowrun/traffic_lights`` channel is registered with the first one, so logs of networks
    without lights have no such topic).

    Metadata and attachments are written first, so even a file cut short by a crash carries
    them. Data is flushed as finished zstd chunks every ``flush_every_s`` seconds of wall
    time (and right after the first logged step), so a killed process leaves a file that
    :func:`flowrun.recording.open_log` salvages up to the last flush. :meth:`close` writes the
    summary and footer; it is idempotent and safe to call from a ``finally`` block.

    Per step the frame is encoded by a :class:`~flowrun.recording.schema.FrameEncoder`
    (protobuf bytes written directly, columns that repeat encoded once) and both messages
    are appended to the open chunk of a :class:`~flowrun.recording.mcap_file.McapWriter`,
    which compresses a chunk when it is full or flushed (``bench/record_write.py`` times it).

    Args:
        path: output file; its parent directory is created.
        metadata: key/value pairs stored in the ``flowrun`` metadata record (versions, seed,
            resolved config, ...).
        attachments: file name -> content (e.g. ``config.yaml``, ``network.net.xml``).
        record_every: keep only steps whose index is a multiple of this (1 keeps all); the
            ``departed``/``arrived`` counts of the steps left out are added to the next
            logged step's, so their sums over a log stay exact.
        flush_every_s: wall-clock seconds between forced chunk flushes (crash safety).
        chunk_size: uncompressed bytes after which a chunk is closed anyway.
        scene: when given, every logged step also gets a ``foxglove.SceneUpdate`` on
            ``/flowrun/scene`` (the road, the cars, the lights: Foxglove's 3D panel).
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
        scene: SceneEncoder | None = None,
    ) -> None:
        if record_every < 1:
            raise RecordingError(f"record_every must be >= 1, got {record_every}")
        self.path = Path(path)
        self.record_every = int(record_every)
        self.flush_every_s = float(flush_every_s)
        self.frames_written = 0
        # The roster as last seen: the objects (identity is checked first) and their values.
        self._roster_objects: tuple[Any, Any, Any] = (None, None, None)
        self._roster: tuple[list[str], list[str], list[bool]] = ([], [], [])
        self._roster_version = 0
        self._encoder = schema.FrameEncoder()
        self._signal_encoder = SignalEncoder()
        self._signals: int | None = None  # channel id, registered with the first SignalFrame
        self._schema_bytes = b""
        # of steps thinned out since the last logged one
        self._departed = self._arrived = self._lane_changes = 0
        self._closed = False
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._stream: IO[bytes] = open(self.path, "wb")  # noqa: SIM115 - closed in close()
        except OSError as err:
            raise RecordingError(f"cannot create MCAP log {self.path}: {err}") from err
        try:
            self._writer = McapWriter(
                self._stream, profile=PROFILE, library="flowrun", chunk_size=chunk_size
            )
            self._scene = scene
            self._write_header(metadata or {}, attachments or {}, scene)
        except BaseException:
            self._stream.close()
            raise
        self._last_flush = time.monotonic()

    def _write_header(
        self, metadata: dict[str, str], attachments: dict[str, bytes], scene: SceneEncoder | None
    ) -> None:
        """The file's metadata and attachments, then the schemas and channels of the vehicle
        frames, the step statistics and (with ``scene``) the Foxglove scene."""
        writer = self._writer
        meta = {str(k): str(v) for k, v in metadata.items()}
        writer.add_metadata(METADATA_NAME, meta, checksum=True)
        for name, data in attachments.items():
            writer.add_attachment(
                name, media_type(name), bytes(data), log_time=0, create_time=time.time_ns()
            )
        schema_bytes = self._schema_bytes = schema.schema_data()
        vehicles_schema = writer.register_schema(
            schema.VEHICLES_TYPE, schema.ENCODING, schema_bytes
        )
        stats_schema = writer.register_schema(schema.STATS_TYPE, schema.ENCODING, schema_bytes)
        self._vehicles = writer.register_channel(
            schema.VEHICLES_TOPIC, schema.ENCODING, vehicles_schema
        )
        self._stats = writer.register_channel(schema.STATS_TOPIC, schema.ENCODING, stats_schema)
        if scene is not None:
            scene_schema = writer.register_schema(SCENE_TYPE, schema.ENCODING, scene_schema_data())
            self._scene_channel = writer.register_channel(
                SCENE_TOPIC, schema.ENCODING, scene_schema
            )

    def _roster_changed(self, frame: VehicleFrame) -> bool:
        """Whether ids/types/RL flags differ from the last frame's (values, not objects)."""
        self._roster_objects = (frame.ids, frame.types, frame.is_rl)
        ids, types, rl = self._roster
        is_rl = np.asarray(frame.is_rl).tolist()
        if frame.ids == ids and frame.types == types and is_rl == rl:
            return False
        self._roster = (list(frame.ids), list(frame.types), is_rl)
        return True

    def write(
        self, frame: VehicleFrame, stats: StepStats, signals: SignalFrame | None = None
    ) -> bool:
        """Log one step unless thinned out by ``record_every``.

        Args:
            frame: every vehicle's state.
            stats: the step's aggregates.
            signals: every traffic light's state (``None`` on networks without lights).

        Returns:
            whether the step was written.
        """
        if self._closed:
            raise RecordingError(f"MCAP log {self.path} is already closed")
        step = frame.step
        if step % self.record_every:
            # entries and exits of a thinned-out step count towards the next logged one
            self._departed += stats.departed
            self._arrived += stats.arrived
            self._lane_changes += stats.lane_changes
            return False
        if self._departed or self._arrived or self._lane_changes:
            stats = replace(
                stats,
                departed=stats.departed + self._departed,
                arrived=stats.arrived + self._arrived,
                lane_changes=stats.lane_changes + self._lane_changes,
            )
            self._departed = self._arrived = self._lane_changes = 0
        stamp = to_ns(frame.time)
        seq = step & 0xFFFFFFFF
        # The kernel passes the same roster objects while the roster holds: check identity
        # first, and compare values only when an object changed.
        ids, types, is_rl = self._roster_objects
        changed = frame.ids is not ids or frame.types is not types or frame.is_rl is not is_rl
        if changed and self._roster_changed(frame):
            self._roster_version = self._roster_version % 0xFFFFFFFF + 1
        add = self._writer.add_message
        # Stats first: if a crash cuts between the two, every salvaged frame has its stats.
        add(self._stats, stamp, schema.encode_stats(stats), stamp, seq)
        add(self._vehicles, stamp, self._encoder.encode(frame, self._roster_version), stamp, seq)
        if signals is not None:
            add(self._signal_channel(), stamp, self._signal_encoder.encode(signals), stamp, seq)
        if self._scene is not None:
            add(self._scene_channel, stamp, self._scene.encode(frame, signals, stamp), stamp, seq)
        self.frames_written += 1
        now = time.monotonic()
        if now - self._last_flush >= self.flush_every_s or self.frames_written == 1:
            self.flush()
            self._last_flush = now
        return True

    def _signal_channel(self) -> int:
        if self._signals is None:
            sid = self._writer.register_schema(
                schema.SIGNALS_TYPE, schema.ENCODING, self._schema_bytes
            )
            self._signals = self._writer.register_channel(
                schema.SIGNALS_TOPIC, schema.ENCODING, sid
            )
        return self._signals

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
            self._writer.add_metadata(
                ROSTER_METADATA, {"rosters": str(self._roster_version)}, checksum=True
            )
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
