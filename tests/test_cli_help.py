"""Help pages: no value metavar on a flag, no line over 80 columns, each option says what it
takes; convert and validate say a .py config's top-level code runs; `flowrun benchmark`
without names is a quick look, `all` by name runs them at full length."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.commands_benchmark import QUICK_STEPS, make_plan
from flowrun.cli.main import COMMANDS, app
from flowrun.experiment.benchmark import BENCHMARKS


def help_of(*argv: str) -> str:
    result = CliRunner().invoke(app, [*argv, "--help"], terminal_width=80)
    assert result.exit_code == 0, result.output
    return result.output


@pytest.mark.parametrize("name", list(COMMANDS))
def test_help_fits_80_columns_and_flags_take_no_value(name: str) -> None:
    text = help_of(name)
    assert max(len(line) for line in text.splitlines()) <= 80
    assert "<bool>" not in text
    # every value an option takes is named: --set KEY=VALUE, --seed N, --out DIR ...
    assert not re.search(r"--[a-z-]+ <(int|str|path|float|list\[\w+\])>", text), text


def test_common_options_name_their_values() -> None:
    text = help_of("baseline")
    for shown in ("--set KEY=VALUE", "--seed N", "--out DIR", "--steps N", "--runs N"):
        assert shown in text
    assert "Usage: flowrun baseline [OPTIONS] {CONFIG}" in text


@pytest.mark.parametrize("name", ["validate", "convert"])
def test_a_config_module_is_said_to_run_its_top_level_code(name: str) -> None:
    assert "top-level code runs" in " ".join(help_of(name).split())


def test_benchmark_out_says_where_its_folder_goes() -> None:
    text = " ".join(help_of("benchmark").split())
    assert "OUT/benchmark/<timestamp>/" in text
    assert "OUT/<config name>" not in text


def test_benchmark_without_names_is_a_quick_look_and_all_is_full_length(tmp_path: Path) -> None:
    quick = make_plan([], 1, None, False, None, False, None, [], tmp_path)
    assert [b.name for b in quick.benchmarks] == list(BENCHMARKS)
    assert quick.sets == (f"env.horizon={QUICK_STEPS}",) and quick.seeds == (0,)
    full = make_plan(["all"], 1, None, False, None, False, None, [], tmp_path)
    assert full.benchmarks == quick.benchmarks and full.sets == ()
    longer = make_plan([], 1, None, False, None, False, None, ["env.horizon=80"], tmp_path)
    assert longer.sets[-1] == "env.horizon=80"  # the user's --set comes last and wins


def test_sweep_plan_is_checked_without_typer(tmp_path: Path) -> None:
    from flowrun.cli.commands_sweep import SweepRequest, prepare_sweep
    from flowrun.errors import ConfigError

    config = Path(__file__).resolve().parent.parent / "configs" / "sugiyama.yaml"
    request = SweepRequest(config, ["network.length=220,240"], seeds=2, steps=10, out=tmp_path)
    plan, backend, run_args = prepare_sweep(request)
    assert backend == "local" and run_args == ["--steps", "10", "--runs", "1"]
    assert len(plan.points) == 4  # 2 lengths x 2 seeds
    with pytest.raises(ConfigError, match="--runs must be >= 1"):
        prepare_sweep(SweepRequest(config, ["network.length=220"], runs=0, out=tmp_path))
