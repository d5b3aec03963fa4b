"""``flowrun baseline`` end to end: the run folder, its MCAP log, signals and bad input."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.loading.loader import load_config
from flowrun.recording.reader import open_log
from flowrun.replay.summary import summarize

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parent.parent
SUGIYAMA = ROOT / "configs" / "sugiyama.yaml"
NOISE = ROOT / "configs" / "sugiyama_noise.yaml"
STEPS = 200


def baseline(out: Path, *args: str, config: Path = SUGIYAMA) -> tuple[Path, Any]:
    """Run ``flowrun baseline`` in-process; return the single run folder it made."""
    result = CliRunner().invoke(app, ["baseline", str(config), "--out", str(out), *args])
    assert result.exit_code == 0, (result.stdout, result.stderr)
    folders = [p for p in out.glob("*/*") if p.is_dir()]
    assert len(folders) == 1, folders
    return folders[0], result


def metrics(run_dir: Path) -> dict[str, Any]:
    data: dict[str, Any] = json.loads((run_dir / "metrics.json").read_text())
    return data


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder, _ = baseline(tmp_path_factory.mktemp("runs"), "--steps", str(STEPS))
    return folder


# --- the run folder ------------------------------------------------------------------------


def test_run_folder_holds_config_command_versions_metrics_and_log(run_dir: Path) -> None:
    assert run_dir.parent.name == "sugiyama"
    assert run_dir.name.endswith("-0")  # <timestamp>-<seed>
    # The resolved config: the file's, with the horizon set by --steps.
    saved = load_config(run_dir / "config.yaml")
    assert saved == load_config(SUGIYAMA, [f"env.horizon={STEPS}"])
    assert saved.env.horizon == STEPS
    assert (run_dir / "command.txt").read_text().strip()
    versions = json.loads((run_dir / "versions.json").read_text())
    assert {"python", "flowrun", "libsumo", "eclipse-sumo"} <= set(versions)
    m = metrics(run_dir)
    assert m["status"] == "complete"
    assert m["seed"] == 0
    assert m["steps_per_run"] == STEPS
    assert m["logs"] == ["run_0.mcap"]
    (run,) = m["runs"]
    assert run["steps"] == STEPS + 1  # the state after reset, then one per step
    assert run["collisions"] == 0
    assert not list(run_dir.glob("*.tmp"))


def test_log_holds_the_speeds_the_simulation_reported(
    run_dir: Path, config: Any, rollout: Any
) -> None:
    log = open_log(run_dir / "run_0.mcap")
    assert not log.salvaged
    frames = list(log.frames())
    assert log.frame_count == len(frames) == STEPS + 1
    assert [f.step for f in frames] == list(range(STEPS + 1))
    assert frames[-1].time - frames[0].time == pytest.approx(STEPS * 0.1)
    # the same seeded run, read straight from the kernel, step by step
    traj = rollout(config("sugiyama"), STEPS)
    np.testing.assert_array_equal(np.array([f.speed for f in frames]), traj.speed)
    np.testing.assert_array_equal(np.array([f.position for f in frames]), traj.position)
    assert log.metadata["seed"] == "0"
    assert log.metadata["config_name"] == "sugiyama"
    assert {"config.yaml", "network.net.xml"} <= set(log.attachments)


def test_metrics_and_replay_summary_agree_with_the_log(run_dir: Path) -> None:
    (run,) = metrics(run_dir)["runs"]
    log = open_log(run_dir / "run_0.mcap")
    per_frame = [float(np.mean(f.speed)) for f in log.frames()]
    assert run["mean_speed"] == pytest.approx(np.mean(per_frame), rel=1e-12)
    assert run["min_speed"] == min(float(np.min(f.speed)) for f in log.frames())
    stats = list(log.stats())
    assert [s.mean_speed for s in stats] == pytest.approx(per_frame, rel=1e-12)
    summary = summarize(log)
    assert summary.mean_speed == pytest.approx(run["mean_speed"], rel=1e-12)
    assert summary.min_speed == pytest.approx(run["min_speed"])
    assert summary.collisions == run["collisions"]
    assert summary.episode_return == pytest.approx(run["episode_return"], rel=1e-9)


# --- options -------------------------------------------------------------------------------


def test_record_every_10_thins_the_log_tenfold(tmp_path: Path) -> None:
    folder, _ = baseline(tmp_path, "--steps", str(STEPS), "--record-every", "10")
    log = open_log(folder / "run_0.mcap")
    steps = [f.step for f in log.frames()]
    assert steps == list(range(0, STEPS + 1, 10))
    assert len(list(log.stats())) == len(steps)
    (run,) = metrics(folder)["runs"]
    assert run["steps"] == STEPS + 1  # metrics still see every step
    assert summarize(log).episode_return == pytest.approx(run["episode_return"], rel=0.05)


def test_two_runs_write_two_logs_with_distinct_seeds(tmp_path: Path) -> None:
    folder, result = baseline(tmp_path, "--steps", "100", "--runs", "2", config=NOISE)
    m = metrics(folder)
    assert m["logs"] == ["run_0.mcap", "run_1.mcap"]
    assert [r["run"] for r in m["runs"]] == [0, 1]
    logs = [open_log(folder / name) for name in m["logs"]]
    assert [log.metadata["seed"] for log in logs] == ["0", "1"]
    last = [list(log.frames())[-1].speed for log in logs]
    assert np.abs(last[0] - last[1]).max() > 1e-3  # noisy drivers, other seed, other run
    assert m["runs"][0]["mean_speed"] != m["runs"][1]["mean_speed"]
    assert "sugiyama_noise: 2 run(s)" in result.stdout


def test_no_record_writes_metrics_but_no_log(tmp_path: Path) -> None:
    folder, _ = baseline(tmp_path, "--steps", "50", "--no-record")
    assert not list(folder.rglob("*.mcap"))
    m = metrics(folder)
    assert m["status"] == "complete"
    assert m["logs"] == []
    assert m["runs"][0]["steps"] == 51
    assert math.isfinite(m["runs"][0]["mean_speed"])


# --- bad input -----------------------------------------------------------------------------


def bad_files(tmp: Path) -> dict[str, Path]:
    good = SUGIYAMA.read_text()
    files = {
        "syntax": "name: x\nsim: {step: 0.1\n",
        "duplicate": good + "name: again\n",
        "unknown": good.replace("bunching: 20", "bunchin: 20"),
    }
    paths = {"missing": tmp / "missing.yaml"}
    for name, text in files.items():
        paths[name] = tmp / f"{name}.yaml"
        paths[name].write_text(text)
    return paths


@pytest.mark.parametrize(
    ("case", "extra", "needle"),
    [
        ("missing", [], "not found"),
        ("syntax", [], "syntax.yaml:3"),
        ("duplicate", [], "duplicate key 'name'"),
        ("unknown", [], "did you mean 'bunching'"),
        ("good", ["--set", "vehicles[0].count=40"], "ring"),
        ("good", ["--steps", "0"], "--steps"),
    ],
)
def test_bad_input_is_one_line_exit_1_and_no_run_folder(
    tmp_path: Path, case: str, extra: list[str], needle: str
) -> None:
    path = SUGIYAMA if case == "good" else bad_files(tmp_path)[case]
    out = tmp_path / "runs"
    result = CliRunner().invoke(app, ["baseline", str(path), "--out", str(out), *extra])
    assert result.exit_code == 1
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    assert needle in lines[0]
    assert "Traceback" not in result.stderr
    assert not out.exists()
