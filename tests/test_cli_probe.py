"""Bad paths and interruptions end in one clear line and the right exit code: a file name
over 255 bytes, ':' and ',' where SUMO would misread them, Ctrl-C before a command starts
and while netconvert runs."""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from flowrun.cli import main as cli_main
from flowrun.cli.main import app
from flowrun.errors import SimulationError

SUGIYAMA = Path(__file__).resolve().parent.parent / "configs" / "sugiyama.yaml"
LONG = "x" * 300


def one_error_line(result: Any, *needles: str) -> str:
    assert result.exit_code == 1, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for needle in needles:
        assert needle in lines[0]
    return str(lines[0])


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("runs")
    result = CliRunner().invoke(app, ["baseline", str(SUGIYAMA), "--steps", "20", "--out",
                                      str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    (path,) = out.glob("sugiyama/*/run_0.mcap")
    return path


@pytest.mark.sumo
@pytest.mark.parametrize(
    "argv",
    [
        ["baseline", str(SUGIYAMA), "--steps", "5", "--out", "{tmp}/" + LONG],
        ["sweep", str(SUGIYAMA), "--grid", "network.length=230", "--steps", "5",
         "--out", "{tmp}/" + LONG],
        ["replay", "{log}", "--csv", "{tmp}/" + LONG + ".csv"],
        ["replay", "{log}", "--plot", "speed", "--out", "{tmp}/" + LONG],
        ["replay", "{tmp}/" + LONG + "/run_0.mcap"],
    ],
    ids=["baseline-out", "sweep-out", "replay-csv", "replay-plot-out", "replay-log"],
)  # fmt: skip
def test_a_name_over_255_bytes_is_one_line(argv: list[str], tmp_path: Path, log: Path) -> None:
    args = [a.format(tmp=tmp_path, log=log) for a in argv]
    result = CliRunner().invoke(app, args)
    one_error_line(result, "file name too long", "allow 255")
    assert "Traceback" not in result.output


def test_a_colon_in_out_is_refused_before_anything_runs(tmp_path: Path) -> None:
    out = tmp_path / "a:b"
    result = CliRunner().invoke(app, ["baseline", str(SUGIYAMA), "--out", str(out)])
    one_error_line(result, "--out", "':'")
    assert not out.exists()


@pytest.mark.parametrize("name", ["sug:iyama", "sug,iyama"])
def test_a_colon_or_comma_in_the_name_is_refused_at_file_line(tmp_path: Path, name: str) -> None:
    config = tmp_path / "c.yaml"
    config.write_text(SUGIYAMA.read_text().replace("name: sugiyama", f'name: "{name}"'))
    line = next(i for i, text in enumerate(config.read_text().splitlines(), 1)
                if text.startswith("name:"))  # fmt: skip
    out = ["--out", str(tmp_path / "o")]
    for argv in (["validate", str(config)], ["baseline", str(config), *out]):
        one_error_line(CliRunner().invoke(app, argv), f"{config}:{line}: name:", repr(name))
    assert not (tmp_path / "o").exists()


def test_ctrl_c_before_a_command_starts_exits_130_without_traceback(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Ctrl-C while the command's modules are imported: a module whose import is interrupted
    (tmp_path / "slow_commands.py").write_text("raise KeyboardInterrupt\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(cli_main.COMMANDS, "baseline", ("slow_commands.x", "Run."))
    result = CliRunner().invoke(app, ["baseline", str(SUGIYAMA)])
    assert result.exit_code == 130
    assert result.stderr == "interrupted\n" and "Traceback" not in result.output


def test_ctrl_c_while_netconvert_runs_is_an_interruption(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def stopped_netconvert(*args: Any, **kwargs: Any) -> Any:
        os.kill(os.getpid(), signal.SIGINT)  # the process group's Ctrl-C reaches flowrun too
        raise SimulationError("netconvert failed on x.edg.xml: stopped by SIGINT")

    monkeypatch.setattr("flowrun.experiment.baseline.run_baseline", stopped_netconvert)
    result = CliRunner().invoke(app, ["baseline", str(SUGIYAMA), "--out", str(tmp_path)])
    assert result.exit_code == 130, result.output
    assert result.stderr.startswith("interrupted: ")


CONSTANT = '''
from flowrun.controllers import BaseController


class Constant(BaseController):
    def __init__(self, veh_id, car_following_params, accel=0.5, fail_safe=None, noise=0):
        super().__init__(veh_id, car_following_params, fail_safe=fail_safe, noise=noise)
        self.accel = accel

    def get_accel(self, env):
        return self.accel
'''


@pytest.mark.sumo
def test_a_controller_module_beside_the_config_is_found(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = tmp_path / "exp"
    folder.mkdir()
    (folder / "my_drivers_near.py").write_text(CONSTANT)
    config = folder / "c.yaml"
    config.write_text(SUGIYAMA.read_text().replace(
        "{type: IDM, v0: 30, T: 1, a: 1, b: 1.5, delta: 4, s0: 2, noise: 0}",
        "{type: 'my_drivers_near:Constant'}",
    ))  # fmt: skip
    assert "my_drivers_near:Constant" in config.read_text()
    monkeypatch.chdir(tmp_path)  # not the config's folder
    monkeypatch.setattr(sys, "path", list(sys.path))
    result = CliRunner().invoke(app, ["baseline", str(config), "--steps", "20", "--out",
                                      str(tmp_path / "o")])  # fmt: skip
    sys.modules.pop("my_drivers_near", None)
    assert result.exit_code == 0, result.output
    (metrics,) = (tmp_path / "o").glob("*/*/metrics.json")
    assert '"collisions": 0' in metrics.read_text()


def test_a_missing_controller_module_says_where_to_put_it(tmp_path: Path) -> None:
    config = tmp_path / "c.yaml"
    config.write_text(SUGIYAMA.read_text().replace(
        "acceleration_controller: {type: IDM", "acceleration_controller: {type: 'nowhere_mod:X'"
    ))  # fmt: skip
    line = one_error_line(CliRunner().invoke(app, ["validate", str(config)]), "nowhere_mod")
    assert "next to the config file" in line and "run from its folder" not in line
