"""What a damaged or unfinished log lost: one :class:`Loss` per damaged part, collected in a
:class:`DamageReport` that the reader fills in as it finds damage (at open for the index,
metadata and attachments; while reading for chunks, whose CRCs are checked when they are
decompressed)."""

from __future__ import annotations

from dataclasses import dataclass, field


def _span(start_s: float | None, end_s: float | None) -> str:
    if start_s is None or end_s is None:
        return ""
    return f"t={start_s:.1f}-{end_s:.1f} s"


@dataclass(frozen=True)
class Loss:
    """One damaged part of a log.

    Attributes:
        part: what was damaged: ``chunk`` (vehicle data), ``metadata``, ``attachment``,
            ``index`` (summary/footer; the data was read by scanning instead), ``tail``
            (bytes after the last readable record), ``unfinished`` (no footer: the writer
            was killed or the file was cut).
        offset: byte offset of the damaged part in the file.
        reason: why it is unusable (e.g. ``CRC mismatch``).
        start_s: first simulation time of the lost data, s (``None`` if unknown or none).
        end_s: last simulation time of the lost data, s (``None`` if unknown or none).
        frames: logged steps lost (``None`` if unknown; 0 when no step was lost).
        name: the metadata record's or attachment's name, when known.
    """

    part: str
    offset: int
    reason: str
    start_s: float | None = None
    end_s: float | None = None
    frames: int | None = None
    name: str = ""

    @property
    def loses_data(self) -> bool:
        """Whether logged steps (vehicle data) were lost, or may have been."""
        return self.part in ("chunk", "tail") and self.frames != 0

    def describe(self) -> str:
        """One readable line: what, where, why, what was lost."""
        what = f"{self.part} {self.name!r}" if self.name else self.part
        lost = [x for x in (_span(self.start_s, self.end_s),) if x]
        if self.frames is not None and self.part in ("chunk", "tail"):
            lost.append(f"{self.frames} logged steps")
        tail = f" - lost {', '.join(lost)}" if lost else ""
        return f"{what} at byte {self.offset}: {self.reason}{tail}"


@dataclass
class DamageReport:
    """Everything found wrong with one log so far (empty for an intact log).

    Chunk damage is found while reading, so a report is complete only after every chunk was
    read (a summary or a CSV export reads them all).

    Attributes:
        losses: the damaged parts, in the order they were found.
    """

    losses: list[Loss] = field(default_factory=list)

    def add(self, loss: Loss) -> bool:
        """Record ``loss`` unless the same part at the same offset is already recorded;
        returns whether it was new."""
        if any(x.part == loss.part and x.offset == loss.offset for x in self.losses):
            return False
        self.losses.append(loss)
        return True

    def __bool__(self) -> bool:
        return bool(self.losses)

    @property
    def data_lost(self) -> bool:
        """Whether logged steps were (or may have been) lost."""
        return any(x.loses_data for x in self.losses)

    @property
    def lost_chunks(self) -> list[Loss]:
        """The chunks (and cut-off tails) that could not be read."""
        return [x for x in self.losses if x.part in ("chunk", "tail")]

    @property
    def frames_lost(self) -> int | None:
        """Logged steps lost, when known for every lost chunk (``None`` otherwise)."""
        counts = [x.frames for x in self.lost_chunks]
        if any(c is None for c in counts):
            return None
        return sum(c for c in counts if c is not None)

    def short(self) -> str:
        """A one-line summary, e.g. ``2 chunks lost (t=10.0-20.0 s, 100 logged steps);
        metadata 'flowrun' lost`` (``""`` when nothing is damaged)."""
        parts: list[str] = []
        chunks = [x for x in self.lost_chunks if x.loses_data]
        if chunks:
            spans = [_span(x.start_s, x.end_s) for x in chunks]
            known = ", ".join(s for s in spans if s)
            frames = self.frames_lost
            extra = [s for s in (known, f"{frames} logged steps" if frames else "") if s]
            noun = "chunk" if len(chunks) == 1 else "chunks"
            parts.append(f"{len(chunks)} {noun} lost" + (f" ({'; '.join(extra)})" if extra else ""))
        for x in self.losses:
            if x.part in ("metadata", "attachment"):
                parts.append(f"{x.part} {x.name!r} lost" if x.name else f"a {x.part} lost")
            elif x.part == "index":
                parts.append("index damaged (data read by scanning)")
            elif x.part == "unfinished":
                parts.append("log not finished (no footer)")
            elif x.part not in ("chunk", "tail"):
                parts.append(f"{x.part} damaged ({x.reason})")
        return "; ".join(parts)

    def describe(self) -> list[str]:
        """One line per damaged part."""
        return [x.describe() for x in self.losses]
