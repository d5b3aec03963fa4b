"""Write a 10,000-step, 2,200-vehicle synthetic log, then time reading it back.

Run: ``PYTHONPATH=. .venv/bin/python bench/replay_read.py [steps] [vehicles]``.
Prints the file size and the wall time of: writing, ``summarize`` (one pass over the speed
column + the stats topic), a 10 % ``--from/--to`` window, and a full ``frames()`` decode.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from flowrun.recording import McapRecorder, open_log
from flowrun.recording.synthetic import ring_frames
from flowrun.replay import summarize


def main() -> None:
    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000
    vehicles = int(sys.argv[2]) if len(sys.argv) > 2 else 2_200
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "big.mcap"
        t0 = time.perf_counter()
        with McapRecorder(path, metadata={"config_name": "bench"}, attachments={}) as rec:
            for frame, stats in ring_frames(vehicles, steps, ring_length=230.0 * vehicles / 22):
                rec.write(frame, stats)
        t1 = time.perf_counter()
        print(
            f"log: {steps} steps x {vehicles} vehicles, {path.stat().st_size / 2**20:.0f} MiB, "
            f"written in {t1 - t0:.1f} s (incl. synthetic data)"
        )

        t0 = time.perf_counter()
        log = open_log(path)
        summary = summarize(log)
        t1 = time.perf_counter()
        print(
            f"open + summarize: {t1 - t0:.2f} s (mean speed {summary.mean_speed:.3f} m/s, "
            f"{summary.logged_steps} steps)"
        )

        end = log.time_range[1] if log.time_range else 0.0
        t0 = time.perf_counter()
        window = summarize(log, start_s=0.45 * end, end_s=0.55 * end)
        t1 = time.perf_counter()
        print(f"summarize --from/--to 10% window: {t1 - t0:.2f} s ({window.logged_steps} steps)")

        t0 = time.perf_counter()
        n = sum(1 for _ in log.frames())
        t1 = time.perf_counter()
        print(f"frames() full decode: {t1 - t0:.2f} s ({n} frames)")


if __name__ == "__main__":
    main()
