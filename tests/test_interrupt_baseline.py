"""SIGINT, SIGTERM and SIGKILL sent to a real ``flowrun baseline`` process at seeded random
moments: the MCAP log is complete (or salvageable after a kill), the run folder says what
happened, the exit code is 128 + signal, and a cut run is never taken for a finished one."""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from flowrun.errors import RecordingError
from flowrun.recording.reader import open_log
from flowrun.rundir.folders import is_complete, read_status

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parent.parent
SUGIYAMA = ROOT / "configs" / "sugiyama.yaml"
FLOWRUN = Path(sys.executable).parent / "flowrun"


def start(out: Path, *args: str) -> subprocess.Popen[str]:
    cmd = [str(FLOWRUN), "baseline", str(SUGIYAMA), "--out", str(out), *args]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for(proc: subprocess.Popen[str], out: Path, pattern: str) -> Path:
    """The first path matching ``pattern`` under ``out`` once it exists (the process runs)."""
    deadline = time.monotonic() + 60
    while True:
        found = sorted(out.glob(pattern))
        if found:
            return found[0]
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, f"{pattern} never appeared"
        time.sleep(0.05)


def signal_at_random_moment(
    tmp_path: Path, sig: int, seed: int, *args: str
) -> tuple[Path, int, str]:
    """Start a long baseline, wait until its first log exists, wait a seeded random time,
    send ``sig``; return the run folder, the exit code and stderr."""
    proc = start(tmp_path, *args)
    try:
        wait_for(proc, tmp_path, "*/*/run_0.mcap")
        time.sleep(random.Random(seed).uniform(0.0, 1.5))
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    (folder,) = tmp_path.glob("*/*")
    return folder, proc.returncode, err


def metrics(folder: Path) -> dict[str, Any]:
    data: dict[str, Any] = json.loads((folder / "metrics.json").read_text())
    return data


LONG = ("--steps", "100000", "--set", "env.horizon=100000")


@pytest.mark.parametrize(
    ("sig", "seed"), [(signal.SIGINT, 1), (signal.SIGTERM, 2)]
)
def test_sigint_and_sigterm_finish_the_log_and_label_the_folder_interrupted(
    tmp_path: Path, sig: int, seed: int
) -> None:
    folder, code, err = signal_at_random_moment(tmp_path, sig, seed, *LONG)
    assert code == 128 + sig, err
    assert "Traceback" not in err
    assert "interrupted" in err
    status = read_status(folder)
    assert status.state == "interrupted"
    assert status.exit_code == 128 + sig
    assert not is_complete(folder)
    m = metrics(folder)
    assert m["status"] == "interrupted"
    assert m["partial"] is True
    (run,) = m["runs"]
    assert 1 <= run["steps"] < 100001
    log = open_log(folder / "run_0.mcap")
    assert not log.salvaged  # finished properly, footer and all
    frames = list(log.frames())
    # every step the metrics counted is in the log: none lost to a chunk cut mid-compression
    assert [f.step for f in frames] == list(range(run["steps"]))
    means = [float(np.mean(f.speed)) for f in frames]
    assert np.mean(means) == pytest.approx(run["mean_speed"], rel=1e-12)
    assert not list(folder.glob(".*.tmp"))


@pytest.mark.parametrize("seed", [4])
def test_sigkill_leaves_a_salvageable_log_and_a_folder_recognisably_cut(
    tmp_path: Path, seed: int
) -> None:
    # Many short runs: a kill lands after some have finished, in the middle of another.
    folder, code, _ = signal_at_random_moment(
        tmp_path, signal.SIGKILL, seed, "--runs", "1000", "--steps", "300"
    )
    assert code == -signal.SIGKILL
    status = read_status(folder)
    assert status.state == "cut"  # said "running", and its process is gone
    assert status.pid is not None
    assert not status.finished
    assert not is_complete(folder)
    m = metrics(folder)
    assert m["status"] == "running"  # never "complete"
    assert m["partial"] is True
    finished = m["runs"]
    assert [r["run"] for r in finished] == list(range(len(finished)))
    assert all(r["steps"] == 301 for r in finished)
    for row in finished:  # every finished run's log is whole and holds what metrics.json says
        log = open_log(folder / f"run_{row['run']}.mcap")
        assert not log.salvaged
        assert log.frame_count == 301
    cut = folder / f"run_{len(finished)}.mcap"
    if cut.exists():  # the run in progress: read what was flushed, from step 0 on, in order
        try:
            steps = [f.step for f in open_log(cut).frames()]
        except RecordingError as err:  # killed between creating the file and its first frame
            assert "no readable data" in str(err)
            assert cut.stat().st_size < 64 * 1024
        else:
            assert steps == list(range(len(steps)))
            assert 1 <= len(steps) <= 301


def test_a_run_whose_pid_was_reused_is_still_cut(tmp_path: Path) -> None:
    # status.json names a live process (this one) that did not write it: its start time differs
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "status.json").write_text(
        json.dumps(
            {"status": "running", "pid": os.getpid(), "pid_start": "1", "host": os.uname()[1]}
        )
    )
    assert read_status(folder).state == "cut"
    (folder / "status.json").write_text("{not json")
    assert read_status(folder).state == "unknown"
    assert not is_complete(folder)
