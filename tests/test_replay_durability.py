"""``flowrun replay`` on a real SUMO log: bad time bounds, outputs that exist or cannot be
written, and damaged copies of the log, through the real CLI app (issues 10 and 16)."""

from __future__ import annotations

import os
import re
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner, Result

from flowrun.cli.main import app
from flowrun.recording import McapLog, open_log

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


def _replay(*args: object) -> Result:
    return CliRunner().invoke(app, ["replay", *map(str, args)])


def _one_error(result: Result) -> str:
    """The run failed cleanly: exit 1, one ``error:`` line, no traceback."""
    assert result.exit_code == 1, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


def _read_all(path: Path) -> McapLog:
    log = open_log(path)
    for _ in log.messages():  # chunk CRCs are checked as chunks are read
        pass
    return log


@pytest.fixture(scope="module")
def sumo_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("runs")
    args = ["baseline", str(CONFIGS / "sugiyama.yaml"), "--set", "env.horizon=200"]
    result = CliRunner().invoke(app, [*args, "--out", str(out)])
    assert result.exit_code == 0, result.output
    (log,) = out.rglob("*.mcap")
    return log


def test_from_nan_is_one_clear_error(sumo_log: Path) -> None:
    assert "--from is NaN" in _one_error(_replay(sumo_log, "--from", "nan"))
    assert "--to is NaN" in _one_error(_replay(sumo_log, "--to", "nan"))


def test_huge_time_bounds_mean_the_whole_log(sumo_log: Path) -> None:
    whole = _replay(sumo_log)
    wide = _replay(sumo_log, "--from", "-1e300", "--to", "1e300")
    assert whole.exit_code == wide.exit_code == 0, wide.output
    assert wide.stdout == whole.stdout
    steps = re.search(r"logged steps\s*│\s*(\d+)", whole.stdout)
    frames = open_log(sumo_log).frame_count
    assert steps is not None and frames and int(steps.group(1)) == frames


def test_a_window_outside_the_log_and_wrong_paths_are_clear_errors(
    sumo_log: Path, tmp_path: Path
) -> None:
    assert "no logged step within --from 1e+300 s" in _one_error(
        _replay(sumo_log, "--from", "1e300")
    )
    # the first frame is the state after reset: 2 steps of 0.1 s (Flow's reset clock)
    assert "the log covers 0.2-" in _one_error(_replay(sumo_log, "--to", "-5"))
    assert "is a folder" in _one_error(_replay(sumo_log.parent))
    message = _one_error(_replay(sumo_log, "--plot", "speed", "--out", sumo_log))
    assert "is a file; give a folder" in message


def test_csv_and_foxglove_never_overwrite(sumo_log: Path, tmp_path: Path) -> None:
    csv = tmp_path / "states.csv"
    first = _replay(sumo_log, "--csv", csv)
    frames = open_log(sumo_log).frame_count
    assert first.exit_code == 0 and frames and csv.read_text().count("\n") == 1 + frames * 22
    csv.write_text("keep me\n")
    assert "never overwrites" in _one_error(_replay(sumo_log, "--csv", csv))
    assert csv.read_text() == "keep me\n"
    fox = tmp_path / "copy.mcap"
    fox.write_bytes(b"mine")
    assert "exists" in _one_error(_replay(sumo_log, "--foxglove", fox))
    assert fox.read_bytes() == b"mine"
    window = tmp_path / "window.mcap"
    assert _replay(sumo_log, "--foxglove", window, "--from", "5", "--to", "6").exit_code == 0
    assert [round(f.time, 1) for f in open_log(window).frames()][::10] == [5.0, 6.0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["copy.mcap", "states.csv", "window.mcap"]


def test_repair_into_a_path_that_cannot_be_written(sumo_log: Path, tmp_path: Path) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    message = _one_error(_replay("--repair", sumo_log, blocker / "fixed.mcap"))
    assert "cannot write the repaired copy" in message
    existing = tmp_path / "there.mcap"
    existing.write_bytes(b"old")
    assert "exists" in _one_error(_replay("--repair", sumo_log, existing))
    assert existing.read_bytes() == b"old"


def test_repair_into_a_read_only_folder(sumo_log: Path, tmp_path: Path) -> None:
    if os.geteuid() != 0:
        folder = tmp_path / "ro"
        folder.mkdir()
        folder.chmod(0o555)
    elif Path("/sys/kernel").is_dir():  # root writes anywhere but in sysfs
        folder = Path("/sys")
    else:
        pytest.skip("running as root without a sysfs: no read-only folder to write into")
    before = sorted(folder.iterdir())
    try:
        message = _one_error(_replay("--repair", sumo_log, folder / "flowrun_fixed.mcap"))
        assert "cannot write the repaired copy" in message
        assert sorted(folder.iterdir()) == before
    finally:
        if folder != Path("/sys"):
            folder.chmod(0o755)


def test_damaged_copies_warn_or_fail_cleanly(
    sumo_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = sumo_log.read_bytes()
    intact = _replay(sumo_log)
    rng = np.random.default_rng(10)
    cases: list[bytes] = []
    for offset in rng.integers(8, len(data), 14):
        flipped = bytearray(data)
        flipped[offset] ^= int(rng.integers(1, 256))
        cases.append(bytes(flipped))
    cases += [data[:cut] for cut in rng.integers(8, len(data), 6)]
    kinds = []
    for i, case in enumerate(cases):
        path = tmp_path / f"case{i}.mcap"
        path.write_bytes(case)
        result = _replay(path, "--csv", tmp_path / f"case{i}.csv")
        assert result.exception is None or isinstance(result.exception, SystemExit), i
        if result.exit_code == 1:
            _one_error(result)
            kinds.append("error")
        elif "warning:" in result.stderr:
            assert "damage" in result.stdout and _read_all(path).salvaged
            kinds.append("salvaged")
        else:
            assert result.exit_code == 0 and not _read_all(path).salvaged
            assert result.stdout.replace(path.name, sumo_log.name) == intact.stdout
            kinds.append("intact")
    with capsys.disabled():
        print(f"\nCLI on damaged SUMO logs ({len(kinds)}): {dict(Counter(kinds))}")
    assert kinds.count("salvaged") >= 10, kinds
