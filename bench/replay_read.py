"""Write a 10,000-step, 2,200-vehicle synthetic log, then time reading it back.

Run: ``PYTHONPATH=. .venv/bin/python bench/replay_read.py [steps] [vehicles]``.
Prints the file size and the wall (and CPU) time of: writing, ``summarize`` (one pass over the
speed column + the stats topic), a 10 % ``--from/--to`` window, a full ``frames()`` decode, and
``verify()`` (every chunk decompressed and CRC-checked). CPU time is the fairer number on a
busy machine. To compare with an older flowrun, run this script with ``PYTHONPATH`` pointing at
a checkout of it (``git archive REV flowrun | tar -x -C /tmp/old``).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from flowrun.recording import McapRecorder, open_log
from flowrun.recording.synthetic import ring_frames
from flowrun.replay import summarize


class _Timer:
    """Wall and CPU seconds of a ``with`` block."""

    def __enter__(self) -> _Timer:
        self.wall, self.cpu = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc: object) -> None:
        self.wall = time.perf_counter() - self.wall
        self.cpu = time.process_time() - self.cpu

    def __str__(self) -> str:
        return f"{self.wall:.2f} s (CPU {self.cpu:.2f} s)"


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

        with _Timer() as t:
            log = open_log(path)
            summary = summarize(log)
        print(
            f"open + summarize: {t} (mean speed {summary.mean_speed:.3f} m/s, "
            f"{summary.logged_steps} steps)"
        )

        end = log.time_range[1] if log.time_range else 0.0
        with _Timer() as t:
            window = summarize(log, start_s=0.45 * end, end_s=0.55 * end)
        print(f"summarize --from/--to 10% window: {t} ({window.logged_steps} steps)")

        with _Timer() as t:
            n = sum(1 for _ in log.frames())
        print(f"frames() full decode: {t} ({n} frames)")

        if hasattr(log, "verify"):  # flowrun before the CRC-checking reader had none
            with _Timer() as t:
                damage = log.verify()
            print(f"verify() every chunk's CRC: {t} ({len(damage.losses)} damaged parts)")


if __name__ == "__main__":
    main()
