"""``eval`` and ``train --resume`` given run folders they cannot use: a baseline run, a
finished training run with nothing left to train, an override file with a mistake in it.
One clear line each, exit 1, and the folder left as it was."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.rundir.folders import mark_done, mark_running

pytest.importorskip("stable_baselines3")

ROOT = Path(__file__).resolve().parent.parent


def run_folder(tmp_path: Path, config: str, metrics: dict[str, object] | None = None) -> Path:
    """A finished run folder holding ``configs/<config>`` (and ``metrics``), no model."""
    folder = tmp_path / "runs" / "x" / "20260101-000000-0"
    folder.mkdir(parents=True)
    shutil.copy(ROOT / "configs" / config, folder / "config.yaml")
    if metrics is not None:
        (folder / "metrics.json").write_text(json.dumps(metrics))
    mark_running(folder)
    mark_done(folder, "complete", exit_code=0)
    return folder


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def one_error(*args: object) -> str:
    result = CliRunner().invoke(app, [str(a) for a in args])
    assert result.exit_code == 1, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.output, result.output
    return lines[0]


@pytest.mark.parametrize("how", [["eval"], ["train", str(ROOT / "configs" / "ring_wave.yaml")]])
def test_a_baseline_run_folder_is_not_taken_for_a_training_run(
    tmp_path: Path, how: list[str]
) -> None:
    folder = run_folder(tmp_path, "sugiyama.yaml")
    before = snapshot(folder)
    args = [*how, folder] if how == ["eval"] else [*how, "--resume", folder]
    error = one_error(*args)
    assert error == (
        f"error: {folder} is not a training run: its config.yaml has no train: section "
        "(a baseline run folder?); pass a folder made by flowrun train"
    )
    assert snapshot(folder) == before


def test_resuming_a_run_that_trained_all_its_steps_says_how_to_continue(tmp_path: Path) -> None:
    folder = run_folder(tmp_path, "ring_wave.yaml", {"status": "complete", "timesteps": 150000})
    before = snapshot(folder)
    error = one_error("train", ROOT / "configs" / "ring_wave.yaml", "--resume", folder)
    assert "already trained 150000 of train.total_timesteps=150000 steps" in error
    assert "--set train.total_timesteps=300000" in error and f"flowrun eval {folder}" in error
    assert snapshot(folder) == before


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("env:\n  horizonn: 5\n", ":2: env.horizonn: unknown key 'horizonn' (did you mean"),
        ("sim:\n  step: 0.1\nenv:\n  horizon: -5\n", ":4: env.horizon: must be greater than 0"),
        ("- 1\n- 2\n", ": expected a mapping of sections to override"),
    ],
)
def test_eval_config_override_errors_name_its_line(
    tmp_path: Path, text: str, expected: str
) -> None:
    folder = run_folder(tmp_path, "ring_wave.yaml")
    override = tmp_path / "override.yaml"
    override.write_text(text)
    error = one_error("eval", folder, "--config", override)
    assert error.startswith(f"error: {override}{expected}"), error
    assert not (folder / "eval").exists()


@pytest.mark.parametrize("kind", ["missing", "folder"])
def test_eval_config_override_that_is_no_file(tmp_path: Path, kind: str) -> None:
    folder = run_folder(tmp_path, "ring_wave.yaml")
    override = tmp_path / "nope.yaml" if kind == "missing" else tmp_path
    error = one_error("eval", folder, "--config", override)
    expected = "config file not found" if kind == "missing" else "is a directory"
    assert error.startswith(f"error: {override}: {expected}"), error


def test_eval_of_a_folder_without_a_model_says_only_that(tmp_path: Path) -> None:
    folder = run_folder(tmp_path, "ring_wave.yaml")
    (folder / "status.json").unlink()  # no status: a run cut before it said anything
    result = CliRunner().invoke(app, ["eval", str(folder)])
    assert result.exit_code == 1
    assert result.stderr == (
        f"error: {folder} has no best_model.zip or final_model.zip; train first (or resume "
        "an interrupted run)\n"
    )
    assert "note" not in result.stdout and not (folder / "eval").exists()


@pytest.mark.sumo
def test_eval_with_an_override_that_changes_the_observations_is_one_line(
    tmp_path: Path,
) -> None:
    import gymnasium as gym
    import numpy as np
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    folder = run_folder(tmp_path, "ring_wave.yaml")
    text = (folder / "config.yaml").read_text()
    (folder / "config.yaml").write_text(text.replace("TRPO", "PPO").replace(
        "normalize: true", "normalize: false"))  # fmt: skip

    class Three(gym.Env[np.ndarray, np.ndarray]):  # the ring_wave policy's spaces
        observation_space = gym.spaces.Box(-np.inf, np.inf, (3,))
        action_space = gym.spaces.Box(-1.0, 1.0, (1,))

    model = PPO("MlpPolicy", make_vec_env(Three), n_steps=8, batch_size=8, seed=0)
    model.save(folder / "final_model.zip")
    args = ["--set", "env.class=AccelEnv", "--set",
            "env.additional_params={max_accel: 1, max_decel: 1, target_velocity: 10, "
            "sort_vehicles: false}"]  # fmt: skip
    error = one_error("eval", folder, *args)
    assert error == (
        "error: the policy in final_model.zip takes observations of shape (3,), but this "
        "config's environment gives (44,); evaluate with the config it was trained on (drop "
        "the --set/--config that changes the environment or its cars)"
    )
    (evaluation,) = (folder / "eval").iterdir()
    assert json.loads((evaluation / "status.json").read_text())["status"] == "failed"


def test_resume_with_out_is_refused_not_ignored(tmp_path: Path) -> None:
    folder = run_folder(tmp_path, "ring_wave.yaml", {"status": "interrupted", "timesteps": 10})
    before = snapshot(folder)
    error = one_error("train", ROOT / "configs" / "ring_wave.yaml", "--resume", folder,
                      "--out", tmp_path / "elsewhere")  # fmt: skip
    assert error == (
        f"error: --out has no effect with --resume: training continues in {folder}; drop --out"
    )
    assert snapshot(folder) == before and not (tmp_path / "elsewhere").exists()
