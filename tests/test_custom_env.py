"""A user's own environment class, named in YAML by import path, with no edit to flowrun."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.envs.factory import env_class, make_env
from flowrun.envs.registry import resolve_env_class
from flowrun.errors import ConfigError
from flowrun.experiment.baseline import run_baseline
from flowrun.kernel.sumo import SumoProcess
from flowrun.loading.loader import load_config

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
CUSTOM = EXAMPLES / "custom_env.yaml"
RING_WAVE = ROOT / "configs" / "ring_wave.yaml"


@pytest.fixture
def fresh_imports(monkeypatch):
    """Undo any ``sys.path`` change and forget ``my_envs``, so each test imports it anew."""
    monkeypatch.setattr(sys, "path", list(sys.path))
    for name in [m for m in sys.modules if m == "my_envs" or m.startswith("my_envs.")]:
        monkeypatch.delitem(sys.modules, name)
    yield
    for name in [m for m in sys.modules if m == "my_envs" or m.startswith("my_envs.")]:
        del sys.modules[name]


def write_config(tmp_path: Path, **env: object) -> Path:
    """``examples/custom_env.yaml`` with its ``env:`` section replaced, in ``tmp_path``."""
    text = CUSTOM.read_text()
    start = text.index("env:\n")
    end = text.index("network:\n")
    lines = "env:\n" + "".join(f"  {k}: {json.dumps(v)}\n" for k, v in env.items())
    path = tmp_path / "custom.yaml"
    path.write_text(text[:start] + lines + text[end:])
    return path


def baseline_cli(*args: str):
    return CliRunner().invoke(app, ["baseline", *args])


def one_error_line(output: str) -> str:
    lines = output.strip().splitlines()
    assert len(lines) == 1, output
    assert lines[0].startswith("error: ")
    assert "Traceback" not in output
    return lines[0]


@pytest.mark.sumo
def test_custom_env_from_yaml_on_pythonpath(fresh_imports, monkeypatch):
    monkeypatch.syspath_prepend(str(EXAMPLES))
    cfg = load_config(CUSTOM)
    env = make_env(cfg)
    try:
        from my_envs.envs import MyEnv

        assert type(env) is MyEnv
        assert env.action_space.shape == (1,)
        assert env.observation_space.shape == (44,)
        obs, _ = env.reset(seed=0)
        for _ in range(20):
            obs, reward, *_ = env.step(np.array([0.5]))
        assert reward == pytest.approx(float(np.mean(obs[22:])), rel=1e-6)
        assert env.k.vehicle.get_speed("rl_0") == pytest.approx(1.0, abs=1e-9)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check_env(env, skip_render_check=True)
    finally:
        env.close()


def test_import_path_is_found_next_to_the_config_without_pythonpath(
    fresh_imports, tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)  # neither the cwd nor sys.path holds my_envs
    with pytest.raises(ConfigError, match=r"cannot import module 'my_envs\.envs'"):
        resolve_env_class("my_envs.envs:MyEnv")
    cls = env_class(load_config(CUSTOM))
    assert cls.__module__ == "my_envs.envs" and cls.__name__ == "MyEnv"
    assert str(EXAMPLES) in sys.path


@pytest.mark.sumo
def test_baseline_cli_runs_the_custom_env_with_pythonpath(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(EXAMPLES)}
    flowrun = Path(sys.executable).parent / "flowrun"  # the console script of this venv
    proc = subprocess.run(
        [
            str(flowrun),
            "baseline",
            "examples/custom_env.yaml",
            "--steps",
            "50",
            "--out",
            str(tmp_path),
        ],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    (metrics,) = tmp_path.glob("custom_env/*/metrics.json")
    data = json.loads(metrics.read_text())
    assert data["status"] == "complete"
    assert data["steps_per_run"] == 50


@pytest.mark.sumo
def test_baseline_cli_runs_the_custom_env_from_another_folder(fresh_imports, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = baseline_cli(str(CUSTOM), "--steps", "20", "--no-record", "--out", "runs")
    assert result.exit_code == 0, result.output
    (metrics,) = tmp_path.glob("runs/custom_env/*/metrics.json")
    assert json.loads(metrics.read_text())["status"] == "complete"


def test_missing_additional_params_are_named_before_sumo_starts(
    fresh_imports, tmp_path, monkeypatch
):
    monkeypatch.syspath_prepend(str(EXAMPLES))

    def no_sumo(self):
        raise AssertionError("SUMO was started")

    monkeypatch.setattr(SumoProcess, "start", no_sumo)
    config = write_config(
        tmp_path, **{"class": "my_envs.envs:MyEnv", "additional_params": {"max_accel": 2}}
    )
    with pytest.raises(ConfigError, match="'max_decel'") as err:
        make_env(load_config(config))
    assert "max_accel" not in str(err.value).replace("'max_decel'", "")
    assert str(config) in str(err.value)

    result = baseline_cli(str(config), "--steps", "5", "--out", str(tmp_path / "runs"))
    assert result.exit_code == 1
    line = one_error_line(result.output)
    assert "'max_decel'" in line and "MyEnv" in line and "env.additional_params" in line
    assert not (tmp_path / "runs").exists()


def test_builtin_env_missing_params_are_all_named(tmp_path):
    config = tmp_path / "ring.yaml"
    config.write_text(
        RING_WAVE.read_text().replace(
            "additional_params: {max_accel: 1, max_decel: 1, ring_length: [220, 270]}",
            "additional_params: {max_accel: 1}",
        )
    )
    result = baseline_cli(str(config), "--steps", "5", "--out", str(tmp_path / "runs"))
    assert result.exit_code == 1
    line = one_error_line(result.output)
    assert "'max_decel'" in line and "'ring_length'" in line
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    ("env_class_name", "expected"),
    [
        ("WaveAttenuationPOEnvv", "did you mean 'WaveAttenuationPOEnv'?"),
        ("my_envs.envs:MyEnvv", "did you mean 'MyEnv'?"),
        ("my_envs.envz:MyEnv", "did you mean 'my_envs.envs'?"),
        ("my_envz.envs:MyEnv", "did you mean 'my_envs'?"),
    ],
)
def test_misspelt_env_class_fails_with_did_you_mean_and_no_run_folder(
    fresh_imports, tmp_path, env_class_name, expected
):
    (tmp_path / "my_envs").symlink_to(EXAMPLES / "my_envs")  # the package beside the config
    config = write_config(
        tmp_path,
        **{"class": env_class_name, "additional_params": {"max_accel": 1, "max_decel": 1}},
    )
    result = baseline_cli(str(config), "--steps", "5", "--out", str(tmp_path / "runs"))
    assert result.exit_code == 1
    line = one_error_line(result.output)
    assert expected in line and "env.class" in line and str(config) in line
    assert not (tmp_path / "runs").exists()


def test_a_class_that_is_not_an_env_is_refused(fresh_imports, monkeypatch):
    monkeypatch.syspath_prepend(str(EXAMPLES))
    with pytest.raises(ConfigError, match=r"not a subclass of flowrun\.envs\.Env"):
        resolve_env_class("my_envs.envs:Box")


def test_a_failing_user_env_marks_its_run_folder_failed(fresh_imports, tmp_path, monkeypatch):
    package = tmp_path / "broken_envs"
    package.mkdir()
    (package / "__init__.py").write_text(
        textwrap.dedent(
            """
            from flowrun.envs import AccelEnv

            class Broken(AccelEnv):
                ADDITIONAL_ENV_PARAMS = {}

                def __init__(self, *args, **kwargs):
                    raise RuntimeError("my bug")
            """
        )
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    cfg = load_config(write_config(tmp_path, **{"class": "broken_envs:Broken"}))
    with pytest.raises(RuntimeError, match="my bug"):
        run_baseline(cfg, steps=5, out=tmp_path / "runs")
    (metrics,) = (tmp_path / "runs").glob("custom_env/*/metrics.json")
    assert json.loads(metrics.read_text())["status"] == "failed"


def test_an_env_class_missing_flows_abstract_methods_is_a_config_error(
    fresh_imports, tmp_path, monkeypatch
):
    package = tmp_path / "half_envs"
    package.mkdir()
    (package / "__init__.py").write_text(
        "from flowrun.envs import Env\n\nclass Half(Env):\n    def get_state(self):\n"
        "        return []\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    cfg = load_config(write_config(tmp_path, **{"class": "half_envs:Half"}))
    with pytest.raises(ConfigError, match="does not implement _apply_rl_actions, action_space"):
        run_baseline(cfg, steps=5, out=tmp_path / "runs")


def test_train_reports_a_misspelt_env_class_before_making_a_run_folder(fresh_imports, tmp_path):
    pytest.importorskip("stable_baselines3")
    (tmp_path / "my_envs").symlink_to(EXAMPLES / "my_envs")
    config = write_config(
        tmp_path,
        **{"class": "my_envs.envs:MyEnvv", "additional_params": {"max_accel": 1, "max_decel": 1}},
    )
    result = CliRunner().invoke(app, ["train", str(config), "--out", str(tmp_path / "runs")])
    assert result.exit_code == 1
    assert "did you mean 'MyEnv'?" in one_error_line(result.output)
    assert not (tmp_path / "runs").exists()
