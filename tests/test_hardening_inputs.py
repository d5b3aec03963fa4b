"""Inputs an adversarial user gives the CLI: out-of-range seeds, folders that are not what a
command expects, files that are not logs. Each is one ``error:`` line, exit 1, no traceback,
and nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.checks import MAX_SEED

ROOT = Path(__file__).resolve().parent.parent
SUGIYAMA = ROOT / "configs" / "sugiyama.yaml"
RING_WAVE = ROOT / "configs" / "ring_wave.yaml"


def one_error(*args: object) -> str:
    result = CliRunner().invoke(app, [str(a) for a in args])
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


@pytest.mark.parametrize("command", ["validate", "baseline", "train", "sweep"])
@pytest.mark.parametrize("seed", [-1, MAX_SEED + 1, 2**32, 10**20])
def test_seed_out_of_range_is_refused_by_name(tmp_path: Path, command: str, seed: int) -> None:
    config = RING_WAVE if command == "train" else SUGIYAMA
    extra = ["--grid", "network.length=230,260"] if command == "sweep" else []
    out = [] if command == "validate" else ["--out", tmp_path / "runs"]
    error = one_error(command, config, "--seed", seed, *extra, *out)
    assert error == f"error: --seed must be between 0 and {MAX_SEED}, got {seed}"
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    ("key", "command", "config"),
    [("sim.seed", "baseline", SUGIYAMA), ("train.seed", "train", RING_WAVE)],
)
def test_a_seed_numpy_cannot_take_is_refused_at_its_line(
    tmp_path: Path, key: str, command: str, config: Path
) -> None:
    section, name = key.split(".")
    data = yaml.safe_load(config.read_text())
    data[section][name] = 2**32  # numpy's legacy seeding (SB3) raised ValueError on it
    path = tmp_path / "exp.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    line = next(
        i + 1
        for i, ln in enumerate(path.read_text().splitlines())
        if ln.strip().startswith(f"{name}: {2**32}")
    )
    error = one_error(command, path, "--out", tmp_path / "runs")
    assert error == f"error: {path}:{line}: {key}: must be between 0 and {MAX_SEED}, got {2**32}"
    assert not (tmp_path / "runs").exists()


def test_validate_takes_seed_as_baseline_does() -> None:
    result = CliRunner().invoke(app, ["validate", str(SUGIYAMA), "--seed", "7"])
    assert result.exit_code == 0, result.output
    assert yaml.safe_load(result.stdout)["sim"]["seed"] == 7


def test_the_largest_seed_is_accepted() -> None:
    result = CliRunner().invoke(app, ["validate", str(SUGIYAMA), "--seed", str(MAX_SEED)])
    assert result.exit_code == 0, result.output
    assert yaml.safe_load(result.stdout)["sim"]["seed"] == MAX_SEED


def test_a_latin1_terminal_gets_question_marks_not_a_traceback(tmp_path: Path) -> None:
    import os
    import subprocess
    import sys

    from flowrun.recording import McapRecorder
    from flowrun.recording.synthetic import ring_frames

    log = tmp_path / "run_0.mcap"
    meta = {"config_name": "sugiyama", "seed": "0", "flowrun_version": "0.1.0",
            "platform_version": "Linux-6.18.0-x86_64-with-glibc2.39",
            "stable_baselines3_version": "2.9.2"}  # fmt: skip
    with McapRecorder(log, metadata=meta, attachments={}) as rec:
        for frame, stats in ring_frames(22, 20):
            rec.write(frame, stats)
    flowrun = str(Path(sys.executable).with_name("flowrun"))
    env = {**os.environ, "PYTHONIOENCODING": "latin-1", "COLUMNS": "30"}  # cells cut with '…'
    done = subprocess.run([flowrun, "replay", str(log)], capture_output=True, env=env)
    assert done.returncode == 0, done.stderr.decode("latin-1")
    out = done.stdout.decode("latin-1")
    assert "?" in out and "mean speed" in out.replace("\n", " ").replace("|", " ")
