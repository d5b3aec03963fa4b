"""The config fuzz through the real CLI (``flowrun validate``): a representative subset of
mutants, paths that are not config files, and ``--set`` with bad paths and values. Each must
print the resolved config (exit 0) or ONE line ``error: <file>:<line>: <key path>: ...``
(exit 1), no traceback, and write nothing."""

from __future__ import annotations

import logging
import os
import random
import re
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from flowrun.cli.main import app as flowrun_app
from tests.config_mutants import SHIPPED, Mutant, data_mutants, text_mutants, write

SUGIYAMA = next(p for p in SHIPPED if p.stem == "sugiyama")


@pytest.fixture
def app() -> typer.Typer:
    return flowrun_app


@pytest.fixture(autouse=True)
def _in_tmp(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.chdir(tmp_path)  # a run folder, if one were made, would appear here
    caplog.set_level(logging.ERROR, logger="flowrun")  # warnings of valid mutants


def one_per_kind(seed: int) -> list[Mutant]:
    """One mutant of each kind, each from a config drawn with ``seed``."""
    rng = random.Random(seed)
    by_kind: dict[str, Mutant] = {}
    for path in rng.sample(SHIPPED, len(SHIPPED)):
        for mutant in [*data_mutants(path, rng, per_leaf=4), *text_mutants(path, rng)]:
            if mutant.kind not in by_kind and rng.random() < 0.2:
                by_kind[mutant.kind] = mutant
    return sorted(by_kind.values(), key=lambda m: m.kind)


def invoke(app: typer.Typer, *args: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["validate", *args])
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    return result.exit_code, result.output


def assert_one_error_line(output: str, location: str) -> None:
    lines = output.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in output, output
    assert lines[0].startswith(f"error: {location}"), output


MUTANTS = one_per_kind(seed=3)


@pytest.mark.parametrize("mutant", MUTANTS, ids=[m.kind for m in MUTANTS])
def test_a_mutant_prints_its_config_or_one_located_error_line(
    app: typer.Typer, tmp_path: Path, mutant: Mutant
) -> None:
    file = write(tmp_path, mutant, 0)
    code, output = invoke(app, str(file))
    if code == 0:
        assert output.startswith("name: "), output
    else:
        assert code == 1
        assert_one_error_line(output, f"{file}:")
        assert re.match(rf"error: {re.escape(str(file))}:\d+: ", output), output
    assert not (tmp_path / "runs").exists()


def test_the_cli_sample_covers_many_kinds() -> None:
    assert len({m.kind for m in MUTANTS}) >= 15


def test_paths_that_are_not_config_files(app: typer.Typer, tmp_path: Path) -> None:
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    empty = tmp_path / "empty.yaml"
    empty.write_text("# nothing here\n")
    cases = {
        str(tmp_path): "is a directory",
        str(fifo): "not a regular file",
        str(tmp_path / "missing.yaml"): "not found",
        str(empty): "empty",
    }
    for path, expected in cases.items():
        code, output = invoke(app, path)
        assert code == 1
        assert_one_error_line(output, path)
        assert expected in output


@pytest.mark.parametrize(
    ("override", "expected"),
    [
        ("sim.step", "key.path=value"),
        ("=1", "key.path=value"),
        ("sim..step=1", "empty name"),
        ("vehicles[x].count=1", "cannot read override key"),
        ("vehicles[9].count=1", "out of range"),
        ("vehicles.id=a", "is a list"),
        ("sim.step.x=1", "not a section"),
        ("sim.stpe=0.2", "did you mean 'step'"),
        ("sim.step=1:30", "expected a number, got '1:30'"),
        ("sim.step=[0.1", "cannot read the value"),
        ("sim.step=.nan", ".nan"),
        ("env.horizon=0.5", "whole number"),
        ("network.length=1e308", "at most"),
        ("vehicles[0].count=-1", "at least 0"),
        ("vehicles[0].acceleration_controller.v0=.inf", "finite"),
        ("initial.spacing=randm", "did you mean 'random'"),
        ("vehicles[0].id=a;b", "SUMO refuses"),
        ("sim.step=10", "shortest edge"),
        ("sim.step={a: [1", "cannot read the value"),
        ("name=../elsewhere", "must not contain '/'"),
        ("name=" + "n" * 300, "at most 100 characters"),
        ("train.hyperparams.gamma=2", "<= 1"),
        ("env.additional_params.max_accel=[1]", "> 0"),
    ],
)
def test_bad_set_paths_and_values_are_one_line_at_set(
    app: typer.Typer, override: str, expected: str
) -> None:
    code, output = invoke(app, str(SUGIYAMA), "--set", override)
    assert code == 1
    assert_one_error_line(output, "--set")
    assert expected in output


@pytest.mark.parametrize(
    ("config", "override", "expected"),
    [
        ("merge", "network.inflows[0].depart_lane=-1", "at least 0"),
        ("merge", "network.inflows[0].depart_lane=5", "has 1 lane(s)"),
        ("merge", "network.inflows[0].depart_speed=warp", "unknown departure speed"),
        ("ring_wave", "train.policy_kwargs.log_std_init=[1]", "expected a number"),
        ("ring_wave", "train.policy_kwargs.net_arch=[64, .nan]", "finite"),
        ("rllib_ring", "train.num_env_runners=-1", ">= 0"),
    ],
)
def test_values_found_by_the_fuzz_are_refused(
    app: typer.Typer, config: str, override: str, expected: str
) -> None:
    path = next(p for p in SHIPPED if p.stem == config)
    code, output = invoke(app, str(path), "--set", override)
    assert code == 1
    assert_one_error_line(output, "--set")
    assert expected in output
