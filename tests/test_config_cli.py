"""``flowrun validate`` and ``flowrun list``, run in-process on their own Typer app."""

from __future__ import annotations

from pathlib import Path

import pytest
import typer
import yaml
from typer.testing import CliRunner

from flowrun.cli.commands_config import register


@pytest.fixture
def app() -> typer.Typer:
    app = typer.Typer()
    register(app)
    return app


@pytest.fixture
def config(tmp_path: Path) -> Path:
    path = tmp_path / "ring.yaml"
    path.write_text(
        "name: ring\n"
        "env: {additional_params: {max_accel: 1, max_decel: 1, target_velocity: 10,"
        " sort_vehicles: false}}\n"
        "network: {type: ring, length: 230}\n"
        "vehicles:\n"
        "  - {id: idm, count: 22, acceleration_controller: IDM}\n"
    )
    return path


def test_validate_prints_the_resolved_config(app: typer.Typer, config: Path) -> None:
    result = CliRunner().invoke(app, ["validate", str(config), "--set", "sim.step=0.5"])
    assert result.exit_code == 0, result.output
    data = yaml.safe_load(result.stdout)
    assert data["sim"]["step"] == 0.5
    assert data["vehicles"][0]["acceleration_controller"] == {"type": "IDM"}
    assert data["initial"]["spacing"] == "uniform"  # defaults are spelled out


@pytest.mark.parametrize(
    ("value", "shown"), [("3000", "3000"), ("3000.0", "3000"), (".inf", ".inf")]
)
def test_validate_prints_step_counts_as_whole_numbers(
    app: typer.Typer, config: Path, value: str, shown: str
) -> None:
    args = ["validate", str(config), "--set", f"env.horizon={value}", "--set", "env.warmup_steps=5"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert f"  horizon: {shown}" in lines and "  warmup_steps: 5" in lines, result.stdout
    horizon = yaml.safe_load(result.stdout)["env"]["horizon"]
    assert type(horizon) is (float if shown == ".inf" else int)


def test_validate_error_is_one_line_and_exit_code_1(app: typer.Typer, config: Path) -> None:
    result = CliRunner().invoke(app, ["validate", str(config), "--set", "vehicles.0.count=x"])
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert lines == ["error: --set: vehicles[0].count: expected an integer, got 'x'"]


def test_validate_missing_file(app: typer.Typer, tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["validate", str(tmp_path / "nope.yaml")])
    assert result.exit_code == 1
    assert "config file not found" in result.output
    assert "Traceback" not in result.output


@pytest.mark.parametrize(
    ("what", "expected"),
    [("controllers", "IDM"), ("networks", "ring"), ("envs", "WaveAttenuationPOEnv")],
)
def test_list_names(app: typer.Typer, what: str, expected: str) -> None:
    result = CliRunner().invoke(app, ["list", what])
    assert result.exit_code == 0, result.output
    assert expected in result.stdout.split()


def test_list_controllers_shows_each_parameter_with_default_unit_and_bounds(
    app: typer.Typer,
) -> None:
    lines = CliRunner().invoke(app, ["list", "controllers"]).stdout.splitlines()
    idm = lines.index("IDM  (IDMController, acceleration)")
    assert lines[idm + 1].strip() == "v0 = 30 m/s, > 0: desired speed"


def test_list_unknown_what_suggests(app: typer.Typer) -> None:
    result = CliRunner().invoke(app, ["list", "netwroks"])
    assert result.exit_code == 1
    assert "did you mean 'networks'?" in result.output
