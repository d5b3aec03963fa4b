"""Two mistakes a user makes in flowrun's YAML that used to run silently: a key of
``env.additional_params`` one letter off a parameter the env declares (refused with a
did-you-mean; other undeclared keys stay accepted, as Flow treats them as free-form), and a
config without its ``network:`` section (an error, not a ring)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.params import EnvParams
from flowrun.envs.additional_params import check_additional_params
from flowrun.envs.base import Env
from flowrun.envs.bottleneck_base import BottleneckEnv
from flowrun.envs.registry import resolve_env_class
from flowrun.envs.test import TestEnv
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config
from flowrun.multiagent.i210 import I210MultiEnv
from flowrun.preflight.checks import validate_config
from flowrun.suggest import one_edit_apart

ROOT = Path(__file__).resolve().parent.parent
SUGIYAMA = (ROOT / "configs" / "sugiyama.yaml").read_text()
FIGURE_EIGHT = (ROOT / "configs" / "figure_eight.yaml").read_text()


def line_of(text: str, needle: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if needle in line)


@pytest.mark.parametrize(
    ("a", "b", "close"),
    [("target_velocty", "target_velocity", True), ("max_acel", "max_accel", True),
     ("max_dcel", "max_decel", True), ("mxa_accel", "max_accel", True),
     ("max_accel", "max_accel", False), ("max_accel", "max_decel", False),
     ("target", "target_velocity", False)],
)  # fmt: skip
def test_one_edit_apart(a: str, b: str, close: bool) -> None:
    assert one_edit_apart(a, b) is close and one_edit_apart(b, a) is close


def test_a_key_one_edit_off_a_declared_parameter_is_refused_at_its_line(tmp_path: Path) -> None:
    assert "target_velocity: 10" in SUGIYAMA
    text = SUGIYAMA.replace("target_velocity: 10", "target_velocty: 99")
    path = tmp_path / "typo.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        validate_config(path)
    err = info.value
    assert err.path == "env.additional_params.target_velocty"
    assert err.location == f"{path}:{line_of(text, 'target_velocty')}"
    assert "did you mean 'target_velocity'" in err.message
    out = CliRunner().invoke(app, ["baseline", str(path), "--out", str(tmp_path / "runs")])
    assert out.exit_code == 1 and "did you mean 'target_velocity'" in out.output
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize("typo", ["relative_position", "relativ_positions"])
def test_a_key_one_edit_off_an_optional_flowrun_option_is_refused_at_its_line(
    tmp_path: Path, typo: str
) -> None:
    text = (ROOT / "configs" / "benchmarks" / "figureeight0.yaml").read_text()
    assert "relative_positions: true" in text
    text = text.replace("relative_positions: true", f"{typo}: true")
    path = tmp_path / "typo.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        validate_config(path)
    err = info.value
    assert err.path == f"env.additional_params.{typo}"
    assert err.location == f"{path}:{line_of(text, typo)}"
    assert "did you mean 'relative_positions'" in err.message
    out = CliRunner().invoke(app, ["baseline", str(path), "--out", str(tmp_path / "runs")])
    assert out.exit_code == 1 and f"{path}:{line_of(text, typo)}" in out.output
    assert "did you mean 'relative_positions'" in out.output


@pytest.mark.parametrize(
    ("cls", "typo", "option"),
    [(BottleneckEnv, "n_crt", "n_crit"), (BottleneckEnv, "feedback_coef", "feedback_coeff"),
     (I210MultiEnv, "lead_ob", "lead_obs"), (TestEnv, "reward_fun", "reward_fn")],
)  # fmt: skip
def test_other_optional_options_are_checked_for_typos(
    cls: type[Env], typo: str, option: str
) -> None:
    params = {**cls.ADDITIONAL_ENV_PARAMS, option: cls.OPTIONAL_ENV_PARAMS[option]}
    check_additional_params(cls, EnvParams(additional_params=params))
    del params[option]
    with pytest.raises(ConfigError, match=f"did you mean '{option}'"):
        check_additional_params(cls, EnvParams(additional_params={**params, typo: 1}))


def test_every_shipped_config_passes_the_typo_check() -> None:
    paths = sorted((ROOT / "configs").rglob("*.yaml"))
    assert len(paths) > 30
    for path in paths:
        env = load_config(path).env
        cls = resolve_env_class(env.env_class, path.parent)
        # configs/envs/ holds default experiments, whose missing keys get the defaults
        given = {**cls.ADDITIONAL_ENV_PARAMS, **env.additional_params}
        check_additional_params(cls, replace(env, additional_params=given))


def test_other_undeclared_keys_stay_free_form(tmp_path: Path) -> None:
    path = tmp_path / "free.yaml"
    path.write_text(SUGIYAMA.replace("target_velocity: 10", "target_velocity: 10, my_weight: 3"))
    assert validate_config(path).env.additional_params["my_weight"] == 3


def test_a_config_without_network_is_an_error_not_a_ring(tmp_path: Path) -> None:
    start = FIGURE_EIGHT.index("network:")
    end = FIGURE_EIGHT.index("\n", start)
    while FIGURE_EIGHT[end + 1] == " ":  # the section's indented lines
        end = FIGURE_EIGHT.index("\n", end + 1)
    path = tmp_path / "no_network.yaml"
    path.write_text(FIGURE_EIGHT[:start] + FIGURE_EIGHT[end + 1 :])
    with pytest.raises(ConfigError, match="no network: section") as info:
        load_config(path)
    assert info.value.location.startswith(str(path)) and info.value.path == "network"
    out = CliRunner().invoke(app, ["baseline", str(path), "--out", str(tmp_path / "runs")])
    assert out.exit_code == 1 and len(out.output.strip().splitlines()) == 1
