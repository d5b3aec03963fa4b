"""``--resume`` keeps what the earlier part wrote; fast evaluation; eval's shared options."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config
from flowrun.rundir.train_state import RunLock, run_state
from flowrun.training.periodic_eval import EVAL_LOG, EVALUATIONS, EvalHistory, numpy_policy

pytestmark = pytest.mark.train
pytest.importorskip("stable_baselines3")

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "ring_wave.yaml"
TINY = [
    "env.horizon=150",
    "env.warmup_steps=0",
    "train.n_envs=2",
    "train.algorithm=PPO",
    "train.hyperparams={n_steps: 128, batch_size: 128, n_epochs: 1}",
    "train.policy_kwargs.net_arch=[16, 16]",
    "train.eval_episodes=1",
    "train.eval_freq=256",
    "train.checkpoint_freq=256",
    "sim.seed=6",
]
runner = CliRunner()


@pytest.fixture(scope="module")
def stopped_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run asked to stop (as by Ctrl-C) after 600 of its 1,024 steps."""
    from flowrun.training.trainer import train

    cfg = load_config(CONFIG, [*TINY, "train.total_timesteps=1024"])
    done = [0]

    def progress(steps: int, total: int, reward: float | None) -> None:
        done[0] = steps

    result = train(cfg, out=tmp_path_factory.mktemp("runs"), progress=progress, argv=["t"],
                   should_stop=lambda: done[0] >= 600)
    assert result.status == "interrupted"
    return result.run_dir


def test_stopped_run_says_interrupted_and_times_its_parts(stopped_run: Path) -> None:
    metrics = json.loads((stopped_run / "metrics.json").read_text())
    assert metrics["status"] == "interrupted" and metrics["partial"] is True
    assert run_state(stopped_run) == "interrupted"
    assert metrics["timesteps"] == 600
    timing = metrics["timing"]
    assert timing["evaluation_s"] > 0 and timing["env_wait_s"] > 0 and timing["update_s"] > 0
    parts = sum(timing[k] for k in ("startup_s", "env_wait_s", "inference_s", "update_s",
                                    "evaluation_s", "checkpoints_s", "finish_s"))
    assert parts == pytest.approx(timing["total_s"], rel=0.15)  # nothing big left out
    history = EvalHistory.load(stopped_run / EVAL_LOG / EVALUATIONS)
    assert history.timesteps == [256, 512]


def test_resume_keeps_monitor_files_evaluations_and_the_best_model(stopped_run: Path) -> None:
    from flowrun.training.trainer import resume_config, train

    history_path = stopped_run / EVAL_LOG / EVALUATIONS
    history = EvalHistory.load(history_path)
    history.add(512, [], 1e9)  # a best score no model can beat (rows filled below)
    history.results[-1] = [1e9]
    history.ep_lengths[-1] = [150]
    history.last_half_speed[-1] = [99.0]
    history.save(history_path)
    best = (stopped_run / "best_model.zip").read_bytes()
    first_part = (stopped_run / "metrics.json").read_text()
    monitors = {p.name: p.read_text() for p in (stopped_run / "monitor").glob("*.csv")}
    assert monitors

    with RunLock(stopped_run):  # a second resume of a folder in use is refused, untouched
        refused = runner.invoke(app, ["train", str(CONFIG), "--resume", str(stopped_run)])
        assert refused.exit_code == 1
        assert "in use by another flowrun train" in refused.output
    assert (stopped_run / "command.txt").read_text().count("\n") == 1

    result = train(resume_config(stopped_run, ["train.total_timesteps=1280"]),
                   resume_dir=stopped_run, argv=["t", "--resume"])
    assert result.status == "complete" and result.resumed_from == 600
    after = EvalHistory.load(history_path)
    assert after.timesteps[:3] == [256, 512, 512] and after.timesteps[3:] == [768, 1024, 1280]
    assert after.results[2] == [1e9]
    assert (stopped_run / "best_model.zip").read_bytes() == best  # no worse model replaced it
    for name, text in monitors.items():  # the earlier episodes are still there, renamed
        kept = stopped_run / "monitor" / name.replace(".monitor.csv", ".before_600.monitor.csv")
        assert kept.read_text() == text
    assert len(list((stopped_run / "monitor").glob("*.csv"))) == 2 * len(monitors)
    assert run_state(stopped_run) == "complete"
    # the earlier part's metrics (its timing) are kept; metrics.json is the resumed part's
    assert (stopped_run / "metrics.before_600.json").read_text() == first_part
    resumed = json.loads((stopped_run / "metrics.json").read_text())
    assert resumed["status"] == "complete" and resumed["partial"] is False


def test_numpy_policy_matches_sb3_predict() -> None:
    import torch

    from flowrun.envs.factory import make_env
    from flowrun.training.algorithms import algorithm_class

    cfg = load_config(CONFIG, TINY)
    env = make_env(cfg)
    cases: list[tuple[str, dict[str, Any]]] = [
        ("PPO", {"net_arch": [16, 16]}),
        ("TRPO", {"net_arch": [8], "activation_fn": torch.nn.ReLU}),
    ]
    try:
        for algorithm, kwargs in cases:
            cls: Any = algorithm_class(algorithm)
            model = cls("MlpPolicy", env, policy_kwargs=kwargs, seed=1, device="cpu")
            act = numpy_policy(model.policy)
            assert act is not None
            obs = np.random.default_rng(0).normal(0, 3, size=(50, 3)).astype(np.float32)
            for o in obs:
                expected, _ = model.predict(o, deterministic=True)
                np.testing.assert_allclose(act(o), expected, atol=1e-5)
            assert any(abs(float(act(o)[0])) < 1 for o in obs)  # not all clipped to the bounds
            # a batch of observations (the numpy evaluation's rings) gives each row's action
            np.testing.assert_allclose(act(obs), np.stack([act(o) for o in obs]), atol=1e-6)
        sac_cls: Any = algorithm_class("SAC")
        sac = sac_cls("MlpPolicy", env, seed=1, device="cpu")
        assert numpy_policy(sac.policy) is None  # SB3's predict is used for other policies
    finally:
        env.close()


def test_eval_help_lists_the_shared_options() -> None:
    result = runner.invoke(app, ["eval", "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0
    for option in ("--out", "--seed", "--set"):
        assert option in result.output


def test_eval_out_and_seed(stopped_run: Path, tmp_path: Path) -> None:
    out = tmp_path / "evals"
    args = ["eval", str(stopped_run), "--out", str(out), "--seed", "17", "--set",
            "env.horizon=50"]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    (folder,) = list(out.iterdir())
    assert folder.name.endswith("-17")
    metrics = json.loads((folder / "metrics.json").read_text())
    assert metrics["status"] == "complete" and metrics["seed"] == 17
    again = runner.invoke(app, args)
    assert again.exit_code == 0
    assert len(list(out.iterdir())) == 2  # never reuses a folder
    first, second = sorted(out.iterdir())
    m1 = json.loads((first / "metrics.json").read_text())
    m2 = json.loads((second / "metrics.json").read_text())
    assert m1["policy"] == m2["policy"]  # same seed, same episodes


def test_evaluation_score_is_the_worst_ring_relative_to_the_all_human_baseline() -> None:
    from dataclasses import replace

    from flowrun.training.periodic_eval import EpisodeRunner

    cfg = load_config(CONFIG, [*TINY, "env.horizon=200",
                               "env.additional_params.ring_length=[220, 270]"])
    runner_ = EpisodeRunner(replace(cfg, env=replace(cfg.env, evaluate=True)), [3, 4])
    try:
        assert all(b > 0 for b in runner_.baseline)
        brake = runner_.run(lambda obs: np.array([-1.0], dtype=np.float32), None)
        coast = runner_.run(lambda obs: np.array([0.5], dtype=np.float32), None)
        assert brake is not None and coast is not None
        # the episodes are spread over the trained lengths, and the worst one ranks the policy
        assert runner_.options == [{"ring_length": 233}, {"ring_length": 258}]
        assert runner_.env.unwrapped.network.length == 258  # the last episode's ring
        ratios = [s.last_half_speed / b for s, b in zip(coast, runner_.baseline, strict=True)]
        assert runner_.score(coast) == pytest.approx(min(ratios))
        assert min(ratios) < max(ratios)
        assert runner_.score(brake) < runner_.score(coast)  # an AV stuck at rest is worse
        assert runner_.run(lambda obs: np.full(1, 0.5, np.float32), None) == coast  # same seeds
    finally:
        runner_.close()


def test_best_by_return_ranks_by_the_mean_evaluation_return_without_a_baseline() -> None:
    from dataclasses import replace

    from flowrun.training.periodic_eval import EpisodeRunner

    cfg = load_config(CONFIG, [*TINY, "env.horizon=200", "train.best_by=return"])
    assert cfg.train is not None and cfg.train.best_by == "return"
    runner_ = EpisodeRunner(replace(cfg, env=replace(cfg.env, evaluate=True)), [3, 4],
                            best_by=cfg.train.best_by)
    try:
        assert all(np.isnan(b) for b in runner_.baseline)  # no all-human episodes played
        coast = runner_.run(lambda obs: np.array([0.5], dtype=np.float32), None)
        assert coast is not None
        returns = [s.episode_return for s in coast]
        assert returns[0] != returns[1]
        assert runner_.score(coast) == pytest.approx(float(np.mean(returns)))
    finally:
        runner_.close()


def test_an_unknown_best_by_is_refused_with_did_you_mean() -> None:
    with pytest.raises(ConfigError, match=r"best-model score 'retrun'.*did you mean 'return'"):
        load_config(CONFIG, [*TINY, "train.best_by=retrun"])
