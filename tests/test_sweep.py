"""``flowrun sweep``: the grid plan (no SUMO), then real sweeps of the Sugiyama ring in parallel
processes: one run folder per point, the table and plot, re-runs that skip finished points, and
an interrupted sweep that keeps what finished and resumes."""

from __future__ import annotations

import csv
import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.errors import ConfigError
from flowrun.experiment.sweep import (
    check_metric,
    finished_folder,
    locked,
    parse_grid,
    plan_sweep,
    split_values,
)
from flowrun.experiment.sweep_report import plot_metric, write_tables
from flowrun.loading.loader import load_config
from flowrun.recording.reader import open_log
from flowrun.rundir.folders import is_complete, read_status

ROOT = Path(__file__).resolve().parent.parent
SUGIYAMA = ROOT / "configs" / "sugiyama.yaml"

# --- the plan ----------------------------------------------------------------------------------


def test_grid_values_split_on_commas_outside_brackets() -> None:
    assert split_values("230, 260,300") == ["230", "260", "300"]
    assert split_values("[1,2],{a: 1, b: 2},x") == ["[1,2]", "{a: 1, b: 2}", "x"]


@pytest.mark.parametrize(
    ("items", "needle"),
    [
        ([], "--grid is required"),
        (["network.length"], "must look like"),
        (["=1,2"], "must look like"),
        (["network.length=230,,260"], "empty value"),
        (["network.length=230,230"], "listed twice"),
        (["network.length=230", "network.length=260"], "given twice"),
        (["sim.seed=1,2"], "use --seeds N"),
    ],
)
def test_a_bad_grid_is_refused(items: list[str], needle: str) -> None:
    with pytest.raises(ConfigError, match=needle):
        parse_grid(items)


def test_the_plan_is_the_product_of_grid_values_and_seeds(tmp_path: Path) -> None:
    cfg = load_config(SUGIYAMA, ["sim.seed=5"])
    axes = parse_grid(["network.length=230,260", "vehicles[0].count=20,21,22"])
    plan = plan_sweep(cfg, axes, 2, tmp_path)
    assert len(plan.points) == 2 * 3 * 2
    assert plan.seeds == (5, 6)
    assert plan.points[0].overrides == ["network.length=230", "vehicles[0].count=20"]
    assert plan.points[0].label == "network.length=230__vehicles[0].count=20__seed=5"
    assert len({p.label for p in plan.points}) == len(plan.points)
    assert plan.folder.parent == tmp_path / "sugiyama"
    # More seeds later: the same sweep folder, so the first seeds' runs are reused.
    assert plan_sweep(cfg, axes, 3, tmp_path).folder == plan.folder
    # Another grid or other run options: another sweep.
    other = parse_grid(["network.length=230,261", "vehicles[0].count=20,21,22"])
    assert plan_sweep(cfg, other, 2, tmp_path).folder != plan.folder
    assert plan_sweep(cfg, axes, 2, tmp_path, ["--steps", "9"]).folder != plan.folder


def test_seeds_past_the_largest_seed_are_refused_before_any_run(tmp_path: Path) -> None:
    axes = parse_grid(["network.length=230"])
    last = load_config(SUGIYAMA, ["sim.seed=2147483646"])
    assert plan_sweep(last, axes, 2, tmp_path).seeds == (2147483646, 2147483647)
    with pytest.raises(ConfigError, match=r"reaches seed 2147483648.*smaller --seed or fewer"):
        plan_sweep(last, axes, 3, tmp_path)


def test_labels_are_safe_folder_names(tmp_path: Path) -> None:
    cfg = load_config(SUGIYAMA)
    plan = plan_sweep(cfg, parse_grid(["name=a/../b,c d"]), 1, tmp_path)
    labels = [p.label for p in plan.points]
    assert all("/" not in label and " " not in label for label in labels)
    assert len(set(labels)) == 2


def test_an_unknown_metric_gets_a_did_you_mean() -> None:
    with pytest.raises(ConfigError, match="did you mean 'outflow'"):
        check_metric("outflw")
    assert check_metric("outflow") == "outflow"


def test_a_cut_or_interrupted_point_is_not_taken_for_finished(tmp_path: Path) -> None:
    plan = plan_sweep(load_config(SUGIYAMA), parse_grid(["network.length=230"]), 1, tmp_path)
    (point,) = plan.points
    folder = plan.folder / point.label
    folder.mkdir(parents=True)
    (folder / "metrics.json").write_text(json.dumps({"status": "complete", "runs": []}))
    for status in (
        {"status": "running", "pid": 2**22 + 1, "host": os.uname()[1]},  # no such process
        {"status": "interrupted", "exit_code": 130},
        {"status": "failed", "error": "x"},
    ):
        (folder / "status.json").write_text(json.dumps(status))
        assert finished_folder(plan, point) is None
    (folder / "status.json").write_text(json.dumps({"status": "complete"}))
    assert finished_folder(plan, point) == folder


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--grid", "network.length=230,5"], "with --grid network.length=5: "),
        (["--grid", "network.lenth=230"], "did you mean 'length'"),
        (["--grid", "network.length=230", "--metric", "outflw"], "did you mean 'outflow'"),
        (["--grid", "network.length=230", "--seeds", "0"], "--seeds must be >= 1"),
        (["--grid", "network.length=230", "--jobs", "0"], "--jobs must be >= 1"),
    ],
)
def test_a_bad_sweep_is_one_line_before_anything_runs(
    tmp_path: Path, args: list[str], needle: str
) -> None:
    out = tmp_path / "runs"
    result = CliRunner().invoke(app, ["sweep", str(SUGIYAMA), "--out", str(out), *args])
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and needle in lines[0], lines
    assert not out.exists()


def test_a_numpy_backend_config_is_refused_once_at_its_line_before_any_point(
    tmp_path: Path,
) -> None:
    config = ROOT / "configs" / "ring_wave_numpy.yaml"
    line = config.read_text().splitlines().index("  backend: numpy") + 1
    out = tmp_path / "runs"
    args = ["sweep", str(config), "--grid", "network.length=230,260", "--out", str(out)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert f"{config}:{line}: sim.backend: flowrun sweep runs on SUMO only" in lines[0]
    assert "--set sim.backend=sumo" in lines[0]
    assert not out.exists()


def test_the_same_sweep_cannot_run_twice_at_once(tmp_path: Path) -> None:
    args = ["sweep", str(SUGIYAMA), "--grid", "network.length=230", "--out", str(tmp_path)]
    plan = plan_sweep(load_config(SUGIYAMA), parse_grid(["network.length=230"]), 1, tmp_path,
                      ["--runs", "1"])  # fmt: skip
    with locked(plan):  # as another sweep process would
        result = CliRunner().invoke(app, args)
    assert result.exit_code == 1
    assert f"already running (pid {os.getpid()})" in result.stderr
    assert [p.name for p in plan.folder.iterdir()] == [".lock"]  # no point started


def test_tables_hold_every_point_and_the_mean_over_seeds(tmp_path: Path) -> None:
    plan = plan_sweep(load_config(SUGIYAMA), parse_grid(["network.length=230,260"]), 2, tmp_path)
    plan.folder.mkdir(parents=True)
    speeds = {("230", 0): 2.0, ("230", 1): 3.0, ("260", 0): 4.0}  # 260/seed 1 was interrupted
    rows = []
    for point in plan.points:
        key = (point.values[0][1], point.seed)
        row = {"network.length": key[0], "seed": point.seed,
               "status": "complete" if key in speeds else "interrupted"}  # fmt: skip
        if key in speeds:
            row["mean_speed"] = speeds[key]
        rows.append(row)
    csv_path, md_path = write_tables(plan, rows, "mean_speed")
    assert [r["mean_speed"] for r in read_csv(csv_path)] == ["2.0", "3.0", "4.0", ""]
    md = md_path.read_text()
    assert "| 260 | 1 | interrupted |" in md
    assert "| 230 | 2/2 | 2.5 +- 0.5 |" in md
    assert "| 260 | 1/2 | 4 +- 0 |" in md
    assert plot_metric(plan, rows, "mean_speed").read_bytes()[:4] == b"\x89PNG"


# --- real sweeps -------------------------------------------------------------------------------


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(f))


@pytest.mark.sumo
def test_a_sweep_runs_each_point_in_its_folder_then_tables_and_plot_and_reruns_skip(
    tmp_path: Path,
) -> None:
    args = ["sweep", str(SUGIYAMA), "--grid", "network.length=230,260", "--steps", "100",
            "--jobs", "2", "--metric", "last_half_mean_speed", "--out", str(tmp_path)]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.stderr
    (folder,) = tmp_path.glob("sugiyama/sweep-*")
    points = sorted(p for p in folder.iterdir() if p.is_dir())
    assert [p.name for p in points] == ["network.length=230__seed=0", "network.length=260__seed=0"]
    pids = {read_status(p).pid for p in points}
    assert len(pids) == 2 and os.getpid() not in pids  # each point in its own process
    assert all(is_complete(p) for p in points)
    rows = read_csv(folder / "results.csv")
    assert [(r["network.length"], r["seed"], r["status"]) for r in rows] == [
        ("230", "0", "complete"),
        ("260", "0", "complete"),
    ]
    for row, point in zip(rows, points, strict=True):
        run = json.loads((point / "metrics.json").read_text())["runs"][0]
        assert float(row["last_half_mean_speed"]) == run["last_half_mean_speed"]
        assert load_config(point / "config.yaml").network.net_params.additional_params[
            "length"
        ] == float(row["network.length"])
    # more room per car: faster traffic
    assert float(rows[1]["last_half_mean_speed"]) > float(rows[0]["last_half_mean_speed"])
    assert "| network.length | seed | status | last_half_mean_speed |" in (
        folder / "results.md"
    ).read_text()
    assert (folder / "last_half_mean_speed.png").read_bytes()[:4] == b"\x89PNG"
    stamps = {p: (p / "status.json").stat().st_mtime_ns for p in points}
    again = CliRunner().invoke(app, args)
    assert again.exit_code == 0, again.stderr
    assert "2 of 2 point(s) already done" in again.stdout
    assert sorted(p for p in folder.iterdir() if p.is_dir()) == points
    assert {p: (p / "status.json").stat().st_mtime_ns for p in points} == stamps


@pytest.mark.sumo
def test_an_interrupted_sweep_keeps_finished_points_and_the_same_command_finishes_it(
    tmp_path: Path,
) -> None:
    cmd = [str(Path(sys.executable).parent / "flowrun"), "sweep", str(SUGIYAMA),
           "--grid", "vehicles[0].count=14,18,22", "--steps", "1500", "--jobs", "1",
           "--no-record", "--out", str(tmp_path)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        second = "sugiyama/sweep-*/vehicles[[]0[]].count=18__seed=0/status.json"
        while not list(tmp_path.glob(second)):  # the second point is running
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline
            time.sleep(0.05)
        time.sleep(random.Random(11).uniform(0.0, 0.3))
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    (folder,) = tmp_path.glob("sugiyama/sweep-*")
    states = {p.name: read_status(p).state for p in folder.iterdir() if p.is_dir()}
    assert states["vehicles[0].count=14__seed=0"] == "complete"
    assert states["vehicles[0].count=18__seed=0"] in {"interrupted", "complete"}
    assert "running" not in states.values() and "cut" not in states.values()
    assert "vehicles[0].count=22__seed=0" not in states  # never started
    rows = read_csv(folder / "results.csv")
    assert rows[0]["status"] == "complete" and rows[2]["status"] == "missing"
    assert rows[1]["status"] == states["vehicles[0].count=18__seed=0"]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=300)
    assert done.returncode == 0, done.stderr
    rows = read_csv(folder / "results.csv")
    assert [r["status"] for r in rows] == ["complete"] * 3
    assert "already done: skipped" in done.stdout
    for name, state in states.items():  # what was there is still there, as it was
        assert read_status(folder / name).state == state


@pytest.mark.sumo
def test_points_of_a_killed_sweep_finish_their_logs_and_say_interrupted(tmp_path: Path) -> None:
    cmd = [str(Path(sys.executable).parent / "flowrun"), "sweep", str(SUGIYAMA),
           "--grid", "network.length=230,260", "--steps", "1000000", "--jobs", "2",
           "--out", str(tmp_path)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while len(list(tmp_path.glob("sugiyama/sweep-*/*/run_0.mcap"))) < 2:
            assert proc.poll() is None
            assert time.monotonic() < deadline
            time.sleep(0.05)
        time.sleep(random.Random(12).uniform(0.0, 0.5))
        proc.kill()  # SIGKILL: the sweep cannot pass anything on; the kernel tells the points
        proc.wait()
        points = sorted(p for p in next(tmp_path.glob("sugiyama/sweep-*")).iterdir() if p.is_dir())
        while any(read_status(p).state == "running" for p in points):
            assert time.monotonic() < deadline, [read_status(p) for p in points]
            time.sleep(0.05)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    for point in points:
        status = read_status(point)
        assert (status.state, status.exit_code) == ("interrupted", 143)
        log = open_log(point / "run_0.mcap")
        assert not log.salvaged
        steps = [f.step for f in log.frames()]
        assert steps == list(range(len(steps)))
