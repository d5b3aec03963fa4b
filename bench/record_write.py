"""Time recording one step to MCAP (µs/step) for 22 and 2,200 vehicles, and its parts.

Run: ``.venv/bin/python bench/record_write.py``. The frames come from
:func:`flowrun.recording.synthetic.ring_frames`, one distinct frame per timed step (cycling a
few frames would let zstd find whole repeated frames and compress unrealistically fast).

Rows:

- ``McapRecorder.write``: the whole per-step cost as ``flowrun baseline`` pays it, from the
  first write to the end of ``close()`` (final chunk's compression and the summary included),
  divided by the steps.
- ``encode_frame`` / ``encode_stats``: protobuf encoding of the two messages.
- ``add_message x2``: ``McapWriter.add_message`` of both messages into the open chunk.
- ``chunk writes``: what joining, CRC, zstd compression and writing of the finished chunks
  add per step (``add_message`` into a file with ``CHUNK_SIZE`` chunks, ``finish()`` included, minus
  the row above).
- ``... with scene``: ``McapRecorder.write`` with the ``/flowrun/scene`` topic (Foxglove's
  ``SceneUpdate``: the cars as cubes, the road once) on a circle road, and how much dearer a
  recorded step is with it. The scene is on by default only if that stays within ~15 %.

Each number is the median of ``--repeats`` runs (default 5); a 2-core machine under load
moves them by ±30%.
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from flowrun.recording import McapRecorder, StepStats, VehicleFrame, schema
from flowrun.recording.mcap_file import CHUNK_SIZE, McapWriter
from flowrun.recording.scene import SceneEncoder
from flowrun.recording.synthetic import ring_frames
from flowrun.render import ring_road

Pairs = list[tuple[VehicleFrame, StepStats]]


def _median_us(run: Callable[[], float], repeats: int) -> float:
    return statistics.median(run() for _ in range(repeats))


def recorder_us(pairs: Pairs, tmp: Path, scene: SceneEncoder | None = None) -> float:
    """µs per step of ``McapRecorder.write`` over ``pairs``, ``close()`` included."""
    path = tmp / "bench.mcap"
    with McapRecorder(path, metadata={"bench": "1"}, attachments={}, scene=scene) as rec:
        start = time.perf_counter()
        for frame, stats in pairs:
            rec.write(frame, stats)
        rec.close()
        elapsed = time.perf_counter() - start
    path.unlink()
    return elapsed / len(pairs) * 1e6


def encode_us(pairs: Pairs) -> tuple[float, float]:
    """µs per step of encoding the frame and the stats."""
    encoder = schema.FrameEncoder()
    start = time.perf_counter()
    for frame, _ in pairs:
        encoder.encode(frame, 1)
    mid = time.perf_counter()
    for _, stats in pairs:
        schema.encode_stats(stats)
    end = time.perf_counter()
    return (mid - start) / len(pairs) * 1e6, (end - mid) / len(pairs) * 1e6


def writer_us(pairs: Pairs, tmp: Path | None) -> float:
    """µs per step of ``McapWriter.add_message`` for both messages (encoded beforehand).

    With ``tmp``, into a file with the recorder's chunk size, ``finish()`` included; without,
    into one chunk that is never written (the append alone).
    """
    encoder = schema.FrameEncoder()
    messages = [(schema.encode_stats(s), encoder.encode(f, 1)) for f, s in pairs]
    stream = io.BytesIO() if tmp is None else open(tmp / "writer.mcap", "wb")  # noqa: SIM115
    with stream:
        chunk_size = 2**62 if tmp is None else CHUNK_SIZE
        writer = McapWriter(stream, chunk_size=chunk_size)
        stats_id = writer.register_channel(schema.STATS_TOPIC, schema.ENCODING)
        frames_id = writer.register_channel(schema.VEHICLES_TOPIC, schema.ENCODING)
        add = writer.add_message
        start = time.perf_counter()
        for step, (stats_data, frame_data) in enumerate(messages):
            stamp = step * 100_000_000
            add(stats_id, stamp, stats_data, stamp, step)
            add(frames_id, stamp, frame_data, stamp, step)
        if tmp is not None:
            writer.finish()
        return (time.perf_counter() - start) / len(messages) * 1e6


def bench(num_vehicles: int, steps: int, repeats: int) -> dict[str, float]:
    """All rows for one ring size."""
    length = 230.0 * num_vehicles / 22
    pairs = list(ring_frames(num_vehicles, steps, ring_length=length))
    encodes = [encode_us(pairs) for _ in range(repeats)]
    with tempfile.TemporaryDirectory() as tmp:
        total = _median_us(lambda: recorder_us(pairs, Path(tmp)), repeats)
        with_scene = _median_us(
            lambda: recorder_us(pairs, Path(tmp), SceneEncoder(ring_road(length))), repeats
        )
        written = _median_us(lambda: writer_us(pairs, Path(tmp)), repeats)
    appended = _median_us(lambda: writer_us(pairs, None), repeats)
    return {
        "McapRecorder.write": total,
        "encode_frame": statistics.median(e[0] for e in encodes),
        "encode_stats": statistics.median(e[1] for e in encodes),
        "add_message x2": appended,
        "chunk writes": written - appended,
        "... with scene": with_scene,
        "scene dearer by %": (with_scene / total - 1) * 100,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"load average {load:.2f}; µs per step, median of {args.repeats} runs")
    for n, steps in ((22, 20_000), (2_200, 500)):
        rows = bench(n, steps, args.repeats)
        print(f"{n:>5} vehicles ({steps} steps)")
        for name, us in rows.items():
            print(f"  {name:<20} {us:9.2f}")


if __name__ == "__main__":
    main()
