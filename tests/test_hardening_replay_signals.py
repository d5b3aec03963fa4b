"""A real SIGTERM/Ctrl-C while ``flowrun replay --plot all`` draws: exit 143/130 with one
``interrupted:`` line, only whole PNGs in the new folder (each listed), no partial files."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flowrun.recording import McapRecorder
from flowrun.recording.synthetic import ring_frames

FLOWRUN = str(Path(sys.executable).with_name("flowrun"))
PNG_END = b"IEND\xaeB`\x82"


@pytest.fixture(scope="module")
def long_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("log") / "ring.mcap"
    meta = {"config_name": "ring", "seed": "0", "flowrun_version": "0.1.0"}
    with McapRecorder(path, metadata=meta, attachments={}) as rec:
        for frame, stats in ring_frames(40, 6000):
            rec.write(frame, stats)
    return path


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_while_plotting_leaves_only_whole_pngs(
    long_log: Path, tmp_path: Path, sig: signal.Signals, code: int
) -> None:
    out = tmp_path / "plots"
    proc = subprocess.Popen(
        [FLOWRUN, "replay", str(long_log), "--plot", "all", "--out", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
    )  # fmt: skip
    deadline = time.monotonic() + 120
    while not (out.is_dir() and any(out.iterdir())):  # the folder is made as drawing starts
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "replay never started plotting"
        time.sleep(0.01)
    os.kill(proc.pid, sig)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == code, stdout + stderr
    assert "Traceback" not in stderr
    assert stderr.strip().splitlines()[-1].startswith("interrupted: plotting stopped; ")
    files = [p for p in out.rglob("*") if p.is_file()]
    assert not [p for p in files if not p.name.endswith(".png")]  # no partial file
    for png in files:
        data = png.read_bytes()
        assert data[:4] == b"\x89PNG" and data.endswith(PNG_END)
        assert f"wrote {png}" in stdout  # every file left is listed
    if not files:
        assert not out.exists() or not any(out.iterdir())
