"""``--out`` paths as users type them: ``~`` the shell left alone, relative folders, characters
SUMO's file options cannot take; and errors that quote a tool's multi-line output."""

from __future__ import annotations

from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from flowrun.cli.common import guarded
from flowrun.cli.main import app
from flowrun.errors import SimulationError

ROOT = Path(__file__).resolve().parent.parent
SUGIYAMA = ROOT / "configs" / "sugiyama.yaml"


@pytest.mark.sumo
@pytest.mark.parametrize("spelling", ["~/runs", "~"])
def test_out_with_a_tilde_the_shell_left_alone_is_the_home_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, spelling: str
) -> None:
    home, cwd = tmp_path / "home", tmp_path / "cwd"
    home.mkdir()
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    monkeypatch.setenv("HOME", str(home))
    args = ["baseline", str(SUGIYAMA), "--steps", "3", "--no-record", f"--out={spelling}"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output  # netconvert expands '~' itself: it failed
    (run,) = (home / spelling[2:] / "sugiyama").iterdir()
    assert (run / "metrics.json").is_file()
    assert list(cwd.iterdir()) == []  # no folder literally named '~'


@pytest.mark.sumo
def test_relative_out_is_under_the_working_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    args = ["baseline", str(SUGIYAMA), "--steps", "3", "--no-record", "--out", "a/../b"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    (run,) = (tmp_path / "b" / "sugiyama").iterdir()
    assert (run / "status.json").is_file()


@pytest.mark.parametrize(
    "command",
    [
        ["baseline", str(SUGIYAMA)],
        ["train", str(ROOT / "configs" / "ring_wave.yaml")],
        ["sweep", str(SUGIYAMA), "--grid", "network.length=230,260", "--steps", "3"],
    ],
)
def test_out_with_a_comma_is_refused_before_sumo_splits_it(
    tmp_path: Path, command: list[str]
) -> None:
    out = tmp_path / "runs,old"
    result = CliRunner().invoke(app, [*command, "--out", str(out)])
    assert result.exit_code == 1, result.output
    (line,) = result.stderr.strip().splitlines()
    assert "',' in a file path as a list separator" in line and str(out) in line
    assert list(tmp_path.iterdir()) == []


def test_a_tools_multi_line_output_in_an_error_is_one_line() -> None:
    demo = typer.Typer()

    @demo.command()
    @guarded
    def fail() -> None:
        raise SimulationError(
            "netconvert failed on x.edg.xml: Error: Could not open nodes-file 'a'.\n"
            "Error: No nodes loaded.\n\nQuitting (on error).\n"
        )

    result = CliRunner().invoke(demo, [])
    assert result.exit_code == 1
    assert result.stderr == (
        "error: netconvert failed on x.edg.xml: Error: Could not open nodes-file 'a'. "
        "Error: No nodes loaded. Quitting (on error).\n"
    )
