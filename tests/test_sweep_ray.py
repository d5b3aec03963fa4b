"""``flowrun sweep --backend ray``: the points of a sweep as Ray tasks on a local Ray instance
give the same run folders and table as a local sweep, re-runs skip finished points, Ctrl-C
reaches the points (Ray workers block SIGINT, their children must not), and a bad backend or an
unreachable cluster is one line before anything is written."""

from __future__ import annotations

import csv
import logging
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner

pytest.importorskip("ray", reason="needs the rllib extra: pip install 'flowrun[rllib]'")

import ray

from flowrun.cli.main import app
from flowrun.recording.reader import open_log
from flowrun.rundir.folders import read_status

SUGIYAMA = Path(__file__).resolve().parent.parent / "configs" / "sugiyama.yaml"
FLOWRUN = str(Path(sys.executable).parent / "flowrun")


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    """One local Ray for the module; the sweep uses it as it is and leaves it running."""
    ray.init(address="local", num_cpus=2, include_dashboard=False, logging_level=logging.WARNING)
    yield
    ray.shutdown()


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(f))


@pytest.mark.sumo
def test_a_ray_sweep_gives_the_local_results_and_a_rerun_skips_finished_points(
    local_ray: None, tmp_path: Path
) -> None:
    args = ["sweep", str(SUGIYAMA), "--grid", "network.length=230,260", "--steps", "100",
            "--metric", "last_half_mean_speed"]  # fmt: skip
    local = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "local")])
    assert local.exit_code == 0, local.stderr
    on_ray = [*args, "--backend", "ray", "--out", str(tmp_path / "ray")]
    result = CliRunner().invoke(app, on_ray)
    assert result.exit_code == 0, result.stderr
    (folder,) = (tmp_path / "ray").glob("sugiyama/sweep-*")
    (local_folder,) = (tmp_path / "local").glob("sugiyama/sweep-*")
    assert folder.name == local_folder.name  # the same sweep, wherever it runs
    rows = read_csv(folder / "results.csv")
    assert [(r["network.length"], r["status"]) for r in rows] == [
        ("230", "complete"),
        ("260", "complete"),
    ]
    assert rows == read_csv(local_folder / "results.csv")  # same seeds => same metrics
    assert float(rows[1]["last_half_mean_speed"]) > float(rows[0]["last_half_mean_speed"])
    md = (folder / "results.md").read_text()
    assert md == (local_folder / "results.md").read_text()
    assert (folder / "last_half_mean_speed.png").read_bytes()[:4] == b"\x89PNG"
    points = sorted(p for p in folder.iterdir() if p.is_dir())
    pids = {read_status(p).pid for p in points}
    assert len(pids) == 2 and os.getpid() not in pids  # each point in its own process
    stamps = {p: (p / "status.json").stat().st_mtime_ns for p in points}
    again = CliRunner().invoke(app, on_ray)
    assert again.exit_code == 0, again.stderr
    assert "2 of 2 point(s) already done" in again.stdout
    assert sorted(p for p in folder.iterdir() if p.is_dir()) == points
    assert {p: (p / "status.json").stat().st_mtime_ns for p in points} == stamps
    assert ray.is_initialized()  # the sweep used the Ray it found and left it running


@pytest.mark.sumo
def test_ctrl_c_reaches_the_points_on_ray_and_pending_points_never_start(
    local_ray: None, tmp_path: Path
) -> None:
    """The sweep attaches to the module's Ray by its address, as to a cluster's head."""
    address = ray.get_runtime_context().gcs_address
    cmd = [FLOWRUN, "sweep", str(SUGIYAMA), "--grid", "vehicles[0].count=14,18,22",
           "--steps", "1000000", "--jobs", "2", "--ray-address", address,
           "--out", str(tmp_path)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while len(list(tmp_path.glob("sugiyama/sweep-*/*/run_0.mcap"))) < 2:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline
            time.sleep(0.1)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    assert "run the same command to go on" in err
    (folder,) = tmp_path.glob("sugiyama/sweep-*")
    points = sorted(p for p in folder.iterdir() if p.is_dir())
    assert [p.name for p in points] == ["vehicles[0].count=14__seed=0",
                                        "vehicles[0].count=18__seed=0"]  # fmt: skip
    for point in points:  # the SIGINT reached each point: it finished its log and said so
        status = read_status(point)
        assert (status.state, status.exit_code) == ("interrupted", 130)
        log = open_log(point / "run_0.mcap")
        assert not log.salvaged and log.frame_count > 1
    rows = read_csv(folder / "results.csv")
    assert [r["status"] for r in rows] == ["interrupted", "interrupted", "missing"]


def test_an_unreachable_ray_address_fails_within_seconds_with_one_line(tmp_path: Path) -> None:
    cmd = [FLOWRUN, "sweep", str(SUGIYAMA), "--grid", "network.length=230",
           "--ray-address", "127.0.0.1:1", "--out", str(tmp_path)]  # fmt: skip
    # timeout: a hang guard, not a speed check (the address check itself waits 5 s at most)
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 1
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("error: cannot reach the Ray cluster at 127.0.0.1:1")
    assert "ray start --head" in lines[0]
    assert not tmp_path.joinpath("sugiyama").exists()  # nothing written


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--backend", "rya"], "did you mean 'ray'"),
        (["--backend", "local", "--ray-address", "127.0.0.1:1"], "drop --backend local"),
    ],
)
def test_a_bad_backend_is_one_line(tmp_path: Path, args: list[str], needle: str) -> None:
    base = ["sweep", str(SUGIYAMA), "--grid", "network.length=230", "--out", str(tmp_path)]
    result = CliRunner().invoke(app, [*base, *args])
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and needle in lines[0], lines
    assert not tmp_path.joinpath("sugiyama").exists()


def test_ray_backend_without_ray_names_the_install_command(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # as if Ray were not installed
    args = ["sweep", str(SUGIYAMA), "--grid", "network.length=230", "--backend", "ray",
            "--out", str(tmp_path)]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert "flowrun sweep --backend ray needs the 'rllib' extra" in lines[0]
    assert "pip install" in lines[0] and "'.[rllib]'" in lines[0]
    assert not tmp_path.joinpath("sugiyama").exists()


def test_a_node_without_the_working_directory_says_the_folders_must_be_shared(
    tmp_path: Path,
) -> None:
    from flowrun.experiment.sweep_ray import run_point_task

    missing = str(tmp_path / "not-on-this-node")
    code, line = run_point_task(["-c", "pass"], missing, flag=None)
    assert code == 1
    assert line.startswith(f"error: the sweep's working directory {missing} does not exist")
    assert "every node mounts at the same path" in line
