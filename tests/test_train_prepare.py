"""Everything flowrun train checks before it starts, without the command line."""

from __future__ import annotations

from pathlib import Path

import pytest

from flowrun.errors import ConfigError, FlowrunError
from flowrun.preflight.prepare import prepare_training

CONFIGS = Path(__file__).resolve().parent.parent / "configs"

pytest.importorskip("stable_baselines3")


def test_a_config_with_a_train_section_is_planned() -> None:
    plan = prepare_training(CONFIGS / "ring_wave.yaml", ["train.total_timesteps=1000"])
    assert plan.rllib is False and plan.train.total_timesteps == 1000 and plan.notes == []


def test_a_bad_hyperparameter_is_refused_at_file_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text((CONFIGS / "ring_wave.yaml").read_text().replace("n_steps:", "n_stepz:"))
    with pytest.raises(ConfigError, match=r"bad\.yaml:\d+: train\.hyperparams\.n_stepz"):
        prepare_training(bad, [])


def test_ray_address_without_rllib_and_out_with_resume_are_refused(tmp_path: Path) -> None:
    with pytest.raises(FlowrunError, match=r"--ray-address is for train\.backend: rllib"):
        prepare_training(CONFIGS / "ring_wave.yaml", [], ray_address="auto")
    with pytest.raises(FlowrunError, match="--out has no effect with --resume"):
        prepare_training(CONFIGS / "ring_wave.yaml", [], resume=tmp_path, out_given=True)


def test_a_baseline_run_folder_is_not_resumed(tmp_path: Path) -> None:
    (tmp_path / "config.yaml").write_text((CONFIGS / "sugiyama.yaml").read_text())
    with pytest.raises(FlowrunError, match="is not a training run"):
        prepare_training(CONFIGS / "sugiyama.yaml", [], resume=tmp_path)
