"""``--out``, ``--seed`` and ``--set``: on every command that runs something, listed in its
``--help``, with one meaning (``--seed`` wins over ``--set sim.seed``; ``--out`` receives the
run folders; ``--set`` changes the saved config)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

from flowrun.cli.common import COMMON_OPTIONS
from flowrun.cli.main import app
from flowrun.loading.loader import load_config

ROOT = Path(__file__).resolve().parent.parent
SUGIYAMA = ROOT / "configs" / "sugiyama.yaml"
#: Commands that run simulations (and write run folders).
RUNNING = ("baseline", "train", "eval", "sweep")


def command(name: str) -> Any:
    """The click command behind ``flowrun NAME`` (typer vendors click: no import of it)."""
    found = typer.main.get_command(app).commands.get(name)  # type: ignore[attr-defined]
    assert found is not None, f"no command {name}"
    return found


def option(name: str, flag: str) -> Any:
    """The option ``flag`` of ``flowrun NAME`` (None when it has none)."""
    for param in command(name).params:
        if param.param_type_name == "option" and flag in param.opts:
            return param
    return None


@pytest.mark.parametrize("name", RUNNING)
def test_every_command_that_runs_something_lists_out_seed_and_set_in_its_help(name: str) -> None:
    result = CliRunner().invoke(app, [name, "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0
    for flag in COMMON_OPTIONS:
        assert flag in result.stdout, f"{name} --help does not list {flag}"
        opt = option(name, flag)
        assert opt is not None and not opt.hidden


@pytest.mark.parametrize("flag", ["--seed", "--set"])
def test_seed_and_set_say_the_same_on_every_command(flag: str) -> None:
    helps = {name: getattr(option(name, flag), "help", None) for name in RUNNING}
    assert len(set(helps.values())) == 1, helps
    assert option("sweep", "--set").multiple
    assert option("baseline", "--set").multiple


def test_validate_takes_set() -> None:
    assert option("validate", "--set") is not None


@pytest.mark.sumo
def test_baseline_seed_wins_over_set_and_out_receives_the_run_folder(tmp_path: Path) -> None:
    out = tmp_path / "elsewhere"
    args = ["--set", "sim.seed=5", "--seed", "3", "--set", "network.length=260"]
    result = CliRunner().invoke(
        app, ["baseline", str(SUGIYAMA), "--out", str(out), "--steps", "5", *args]
    )
    assert result.exit_code == 0, result.stderr
    (folder,) = out.glob("sugiyama/*")
    assert folder.name.endswith("-3")
    saved = load_config(folder / "config.yaml")
    assert saved.sim.seed == 3
    assert saved.network.net_params.additional_params["length"] == 260
    assert json.loads((folder / "metrics.json").read_text())["seed"] == 3
    assert list(tmp_path.iterdir()) == [out]  # nothing outside --out
