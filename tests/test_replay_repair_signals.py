"""``flowrun replay --repair`` stopped by SIGINT, SIGTERM or SIGKILL in the middle of writing
(a real subprocess, a real signal): the input is never touched, and the output is either
complete or absent under its final name (issue 10 item 2)."""

from __future__ import annotations

import hashlib
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flowrun.recording import McapRecorder, open_log
from flowrun.recording.synthetic import ring_frames

FLOWRUN = Path(sys.executable).parent / "flowrun"
STEPS = 800  # 2,200 cars: ~22 MiB, a repair of a second or more


@pytest.fixture(scope="module")
def big_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("big") / "big.mcap"
    with McapRecorder(path, metadata={"config_name": "big"}, attachments={}) as rec:
        for frame, stats in ring_frames(2200, STEPS, ring_length=23_000.0):
            rec.write(frame, stats)
    return path


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _wait_for(predicate: object, what: str, proc: subprocess.Popen[bytes]) -> None:
    """Poll until ``predicate()`` or the process ends (a hang guard, not a timing check)."""
    deadline = time.monotonic() + 120
    while not predicate():  # type: ignore[operator]
        if proc.poll() is not None:
            return
        if time.monotonic() > deadline:
            proc.kill()
            pytest.fail(f"timed out waiting for {what}")
        time.sleep(0.005)


@pytest.mark.parametrize(
    ("signum", "code"),
    [(signal.SIGINT, 130), (signal.SIGTERM, 143), (signal.SIGKILL, -signal.SIGKILL)],
)
def test_repair_interrupted_leaves_input_intact_and_no_half_output(
    big_log: Path, tmp_path: Path, signum: int, code: int
) -> None:
    before = _digest(big_log)
    out = tmp_path / "fixed.mcap"
    proc = subprocess.Popen(
        [str(FLOWRUN), "replay", "--repair", str(big_log), str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    _wait_for(lambda: any(tmp_path.glob("*.partial")), "the repair to start writing", proc)
    interrupted = proc.poll() is None
    if interrupted:
        proc.send_signal(signum)
    try:
        _, err = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("the repair did not stop after the signal")
    assert _digest(big_log) == before  # the input is only read
    assert b"Traceback" not in err, err.decode()
    if proc.returncode == 0:  # it finished before the signal landed: a complete copy
        log = open_log(out)
        assert not log.salvaged and log.frame_count == STEPS
        return
    assert interrupted and proc.returncode == code, (proc.returncode, err.decode())
    assert not out.exists()  # never a half file under the final name
    partial = list(tmp_path.glob("*.partial"))
    if signum == signal.SIGKILL:
        assert len(partial) <= 1  # a killed repair leaves only its recognisable .partial
    else:
        assert partial == []  # cleaned up on the way out
        assert err.decode().startswith("interrupted: repair stopped; nothing was written")
