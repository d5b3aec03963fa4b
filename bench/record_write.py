"""Time encoding + writing one frame to MCAP (µs/frame) for 22 and 2,200 vehicles.

Run: ``.venv/bin/python bench/record_write.py``. Includes protobuf encoding, the mcap
writer's chunk building and the amortised zstd compression of finished chunks.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

from flowrun.recording import McapRecorder
from flowrun.recording.synthetic import ring_frames


def bench(num_vehicles: int, steps: int, repeats: int = 3) -> float:
    frames = list(ring_frames(num_vehicles, 200, ring_length=230.0 * num_vehicles / 22))
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(repeats):
            path = Path(tmp) / f"b{r}.mcap"
            with McapRecorder(path, metadata={"bench": "1"}, attachments={}) as rec:
                start = time.perf_counter()
                for i in range(steps):
                    frame, stats = frames[i % len(frames)]
                    rec.write(frame, stats)
                rec.close()  # include the final chunk's compression
                results.append((time.perf_counter() - start) / steps * 1e6)
    return statistics.median(results)


def main() -> None:
    for n, steps in ((22, 20_000), (2_200, 500)):
        us = bench(n, steps)
        print(f"{n:>5} vehicles: {us:8.1f} µs/frame ({us / n:.2f} µs/vehicle)")


if __name__ == "__main__":
    main()
