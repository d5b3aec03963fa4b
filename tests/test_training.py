"""Training and evaluation: real (short, seeded) stable-baselines3 runs and their pieces."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.params import is_rl
from flowrun.config.schedules import LinearSchedule, parse_schedule
from flowrun.errors import ConfigError, TrainingError
from flowrun.loading.loader import load_config
from flowrun.training import deps
from flowrun.training.evaluate import all_human

pytestmark = pytest.mark.train
pytest.importorskip("stable_baselines3")

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "ring_wave.yaml"
# A tiny version of the ring experiment: 200 steps per episode, no warm-up, small updates.
SMALL = [
    "env.horizon=200",
    "env.warmup_steps=0",
    "train.n_envs=2",
    "train.algorithm=PPO",
    "train.hyperparams={n_steps: 256, batch_size: 128, n_epochs: 2}",
    "train.policy_kwargs.net_arch=[16, 16]",
    "train.eval_episodes=1",
]
runner = CliRunner()


def _set(items: list[str]) -> list[str]:
    return [arg for item in items for arg in ("--set", item)]


def _only_run(out: Path) -> Path:
    (run,) = list((out / "ring_wave").iterdir())
    return run


def test_short_training_writes_a_model_that_eval_rolls_out(tmp_path: Path) -> None:
    steps = [*SMALL, "train.total_timesteps=1024", "train.eval_freq=512",
             "train.checkpoint_freq=512"]
    result = runner.invoke(app, ["train", str(CONFIG), "--seed", "3", "--out", str(tmp_path),
                                 *_set(steps)])
    assert result.exit_code == 0, result.output
    run = _only_run(tmp_path)
    assert run.name.endswith("-3")
    for name in ("config.yaml", "command.txt", "versions.json", "final_model.zip",
                 "best_model.zip", "metrics.json", "checkpoints/state.json"):
        assert (run / name).is_file(), name
    assert any((run / "tensorboard").rglob("events.out.tfevents.*"))
    train_metrics = json.loads((run / "metrics.json").read_text())
    assert train_metrics["status"] == "complete"
    assert train_metrics["timesteps"] == 1024

    result = runner.invoke(app, ["eval", str(run), "--model", "final", "--episodes", "1",
                                 "--set", "env.additional_params.ring_length=[230, 230]"])
    assert result.exit_code == 0, result.output
    assert "policy" in result.output
    evals = sorted((run / "eval").iterdir())
    assert len(evals) == 2  # the one after training and this one
    metrics = json.loads((evals[-1] / "metrics.json").read_text())
    assert metrics["model"].endswith("final_model.zip")
    for side in ("policy_mean", "baseline_mean"):
        for key in ("mean_speed", "last_half_mean_speed", "speed_std", "min_speed",
                    "episode_return"):
            assert math.isfinite(metrics[side][key]), (side, key)
    from flowrun.recording.reader import open_log

    for name in ("policy_0.mcap", "baseline_0.mcap"):
        log = open_log(evals[-1] / name)
        assert log.frame_count == 201  # initial state + 200 steps


def test_interrupted_training_saves_a_checkpoint_and_resume_reaches_the_total(
    tmp_path: Path,
) -> None:
    from stable_baselines3 import PPO

    from flowrun.training.trainer import resume_config, train

    cfg = load_config(CONFIG, [*SMALL, "train.total_timesteps=1024", "sim.seed=5"])

    def stop_midway(done: int, total: int, reward: float | None) -> None:
        if done >= 600:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        train(cfg, out=tmp_path, progress=stop_midway, argv=["test"])
    run = _only_run(tmp_path)
    state = json.loads((run / "checkpoints" / "state.json").read_text())
    assert state["timesteps"] == 600
    assert json.loads((run / "metrics.json").read_text())["status"] == "interrupted"

    result = train(resume_config(run, ["train.total_timesteps=2048"]), resume_dir=run,
                   argv=["test", "--resume"])
    assert result.status == "complete"
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["resumed_from"] == 600
    model = PPO.load(run / "final_model.zip", device="cpu")
    assert model.num_timesteps >= 2048
    assert model.num_timesteps == result.timesteps
    assert (run / "config.before_600.yaml").is_file()  # the total changed on resume


def test_resume_without_a_checkpoint_is_a_clear_error(tmp_path: Path) -> None:
    (tmp_path / "config.yaml").write_text(CONFIG.read_text())
    result = runner.invoke(app, ["train", str(CONFIG), "--resume", str(tmp_path)])
    assert result.exit_code == 1
    assert "no checkpoint to resume from" in result.output


def test_hyperparameter_typo_is_a_config_error_with_did_you_mean() -> None:
    from flowrun.training.algorithms import build_hyperparams

    with pytest.raises(ConfigError) as err:
        build_hyperparams("PPO", {"n_step": 128})
    assert err.value.path == "train.hyperparams.n_step"
    assert "did you mean 'n_steps'" in err.value.message


def test_hyperparameter_typo_stops_train_before_any_run_folder(tmp_path: Path) -> None:
    result = runner.invoke(app, ["train", str(CONFIG), "--out", str(tmp_path),
                                 "--set", "train.hyperparams.learnig_rate=0.001"])
    assert result.exit_code == 1
    assert "train.hyperparams.learnig_rate" in result.output
    assert "did you mean 'learning_rate'" in result.output
    assert not (tmp_path / "ring_wave").exists()


def test_reserved_and_algorithm_specific_hyperparameters() -> None:
    from flowrun.training.algorithms import build_hyperparams

    with pytest.raises(ConfigError, match=r"train\.seed"):
        build_hyperparams("SAC", {"seed": 1})
    with pytest.raises(ConfigError, match="SAC has no hyper-parameter 'n_epochs'"):
        build_hyperparams("SAC", {"n_epochs": 3})
    built = build_hyperparams(
        "TD3", {"action_noise": {"normal": 0.2}, "train_freq": [1, "episode"]}, action_dim=1
    )
    assert built["action_noise"]().shape == (1,)
    assert built["train_freq"] == (1, "episode")
    assert build_hyperparams("TRPO", {"target_kl": 0.02}) == {"target_kl": 0.02}


def test_schedules_are_data_functions_of_progress_remaining() -> None:
    lr = parse_schedule({"linear": 3e-4}, "train.hyperparams.learning_rate")
    assert isinstance(lr, LinearSchedule)
    assert lr(1.0) == pytest.approx(3e-4)
    assert lr(0.5) == pytest.approx(1.5e-4)
    assert lr(0.0) == 0.0
    ranged = parse_schedule({"linear": [3e-4, 1e-5]}, "p")
    assert callable(ranged) and ranged(0.0) == pytest.approx(1e-5)
    assert parse_schedule({"constant": 0.2}, "p") == 0.2
    assert parse_schedule(0.1, "p") == 0.1
    with pytest.raises(ConfigError, match="did you mean 'linear'"):
        parse_schedule({"linaer": 3e-4}, "train.hyperparams.learning_rate")
    with pytest.raises(ConfigError, match="expected a number"):
        parse_schedule({"linear": "3e-4*2"}, "p")


def test_missing_train_extra_says_how_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    def missing(name: str) -> object:
        raise ModuleNotFoundError(f"No module named '{name}'", name="torch")

    monkeypatch.setattr(deps, "import_module", missing)
    with pytest.raises(TrainingError, match="torch"):
        deps.require()
    result = runner.invoke(app, ["train", str(CONFIG)])
    assert result.exit_code == 1
    assert "pip install torch==2.13.0" in result.output
    assert "pip install -e '.[train]'" in result.output


def test_all_human_baseline_drives_the_av_like_the_humans() -> None:
    cfg = load_config(CONFIG)
    human = all_human(cfg)
    assert cfg.vehicles.num_rl_vehicles == 1
    assert human.vehicles.num_rl_vehicles == 0
    assert human.vehicles.num_vehicles == cfg.vehicles.num_vehicles
    idm = cfg.vehicles.groups[0].acceleration_controller
    assert all(g.acceleration_controller == idm for g in human.vehicles.groups)
    assert not any(is_rl(g) for g in human.vehicles.groups)


def test_a_config_of_only_rl_cars_is_evaluated_without_an_all_human_baseline() -> None:
    from flowrun.training.comparison import all_human_or_none

    benchmarks = Path(__file__).resolve().parents[1] / "configs" / "benchmarks"
    only_rl = load_config(benchmarks / "figureeight2.yaml")  # 14 AVs, no human group
    assert all_human_or_none(only_rl) is None
    mixed = all_human_or_none(load_config(benchmarks / "figureeight0.yaml"))
    assert mixed is not None
    assert {g.acceleration_controller.type for g in mixed.vehicles.groups} == {"IDM"}
