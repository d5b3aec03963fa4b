"""``flowrun replay`` run in-process on its own Typer app."""

from __future__ import annotations

from pathlib import Path

import pytest
import typer
from mcap.reader import make_reader
from typer.testing import CliRunner, Result

from flowrun.cli.commands_replay import register
from flowrun.recording import McapRecorder, open_log
from flowrun.recording.synthetic import ring_frames

META = {"config_name": "ring", "seed": "0", "flowrun_version": "0.1.0"}


@pytest.fixture
def app() -> typer.Typer:
    app = typer.Typer()

    @app.callback()
    def _root() -> None:  # keep "replay" a subcommand, as in the real app
        pass

    register(app)
    return app


def _record(path: Path, steps: int = 200, chunk_size: int = 4 * 1024 * 1024) -> Path:
    with McapRecorder(path, metadata=META, attachments={}, chunk_size=chunk_size) as rec:
        for frame, stats in ring_frames(22, steps):
            rec.write(frame, stats)
    return path


def run(app: typer.Typer, *args: object) -> Result:
    return CliRunner().invoke(app, ["replay", *map(str, args)])


def test_summary_table(app: typer.Typer, tmp_path: Path) -> None:
    log = _record(tmp_path / "a.mcap")
    result = run(app, log)
    assert result.exit_code == 0, result.output
    out = result.stdout
    for label in ("mean speed", "min speed", "collisions", "idm: 21", "ring (seed 0)"):
        assert label in out


def test_window_vehicles_csv_and_plots(app: typer.Typer, tmp_path: Path) -> None:
    log = _record(tmp_path / "a.mcap")
    result = run(
        app,
        log,
        "--from",
        5,
        "--to",
        10,
        "--vehicles",
        "idm_1,idm_2",
        "--csv",
        tmp_path / "e.csv",
        "--plot",
        "all",
        "--out",
        tmp_path / "plots",
    )
    assert result.exit_code == 0, result.output
    assert len((tmp_path / "e.csv").read_text().splitlines()) == 1 + 2 * 51
    (folder,) = (tmp_path / "plots").iterdir()  # a new folder per replay: a-<timestamp>
    assert folder.name.startswith("a-")
    for name in ("speeds.png", "time_space.png", "vehicle_speeds.png"):
        assert (folder / name).stat().st_size > 0


def test_compare_two_logs(app: typer.Typer, tmp_path: Path) -> None:
    a = _record(tmp_path / "a.mcap")
    b = _record(tmp_path / "b.mcap", steps=100)
    result = run(app, a, b, "--plot", "speed", "--out", tmp_path / "p")
    assert result.exit_code == 0, result.output
    assert "A: a.mcap" in result.stdout and "B: b.mcap" in result.stdout
    (folder,) = (tmp_path / "p").iterdir()
    assert folder.name.startswith("a-vs-b-") and (folder / "speeds.png").exists()


def test_not_mcap_is_one_line_error(app: typer.Typer, tmp_path: Path) -> None:
    bad = tmp_path / "x.mcap"
    bad.write_text("not a log\n")
    result = run(app, bad)
    assert result.exit_code == 1
    err = result.stderr
    assert "not an MCAP file" in err and len(err.strip().splitlines()) == 1
    assert "Traceback" not in result.output


def test_truncated_log_is_salvaged_with_a_warning(app: typer.Typer, tmp_path: Path) -> None:
    log = _record(tmp_path / "a.mcap", steps=300, chunk_size=30_000)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(log.read_bytes()[: log.stat().st_size * 2 // 3])
    result = run(app, cut)
    assert result.exit_code == 0, result.output
    assert "salvaged" in result.stderr


def test_repair_writes_clean_copy(app: typer.Typer, tmp_path: Path) -> None:
    log = _record(tmp_path / "a.mcap", steps=300, chunk_size=30_000)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(log.read_bytes()[: log.stat().st_size // 2])
    fixed = tmp_path / "fixed.mcap"
    result = run(app, "--repair", cut, fixed)
    assert result.exit_code == 0, result.output
    with open(fixed, "rb") as f:
        assert make_reader(f).get_summary() is not None
    assert not open_log(fixed).salvaged
    again = run(app, cut, "--repair", fixed)  # never overwrites
    assert again.exit_code == 1


def test_foxglove_export_of_a_window(app: typer.Typer, tmp_path: Path) -> None:
    log = _record(tmp_path / "a.mcap")
    out = tmp_path / "fox.mcap"
    result = run(app, log, "--from", 1, "--to", 2, "--vehicles", "rl_0", "--foxglove", out)
    assert result.exit_code == 0, result.output
    frames = list(open_log(out).frames())
    assert len(frames) == 11 and all(f.ids == ["rl_0"] for f in frames)


@pytest.mark.parametrize(
    "args",
    [
        ["--from", "5", "--to", "1"],
        ["--vehicles", "nobody"],
    ],
)
def test_bad_options_exit_1(app: typer.Typer, tmp_path: Path, args: list[str]) -> None:
    log = _record(tmp_path / "a.mcap", steps=20)
    result = run(app, log, *args)
    assert result.exit_code == 1


def test_three_logs_is_an_error(app: typer.Typer, tmp_path: Path) -> None:
    log = _record(tmp_path / "a.mcap", steps=5)
    assert run(app, log, log, log).exit_code == 1
