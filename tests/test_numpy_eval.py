"""``train.eval_backend: numpy``: the periodic evaluation's episodes on the numpy rings equal
the SUMO evaluation's, and training with it picks its best model from them."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.params import VehicleParams, is_rl
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config
from flowrun.training.numpy_eval import NumpyEpisodeRunner, numpy_eval_plan
from flowrun.training.periodic_eval import EpisodeRunner

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[1]
RING = ROOT / "configs" / "ring_wave.yaml"
SHORT = ["env.horizon=400", "env.warmup_steps=200"]


def feedback_policy(obs: np.ndarray) -> np.ndarray:
    """A policy whose actions depend on its observations (one row or a batch of rows), so
    any difference between the backends would feed back into the trajectories."""
    o = np.asarray(obs, dtype=np.float64)
    a = -7.5 * o[..., 1:2] + 0.03 * (270 * o[..., 2:3] - 20) - 0.2 * o[..., 0:1]
    return np.clip(a, -1, 1).astype(np.float32)


def test_numpy_episodes_equal_the_sumo_evaluation_episodes() -> None:
    cfg = load_config(RING, SHORT)
    seeds = [10_000, 10_001, 10_002]
    fast = NumpyEpisodeRunner(cfg, seeds)
    sumo = EpisodeRunner(replace(cfg, env=replace(cfg.env, evaluate=True)), seeds)
    try:
        # spread over the trained lengths as on SUMO: 228, 245 and 262 m
        assert fast.lengths == [228.0, 245.0, 262.0]
        assert [o["ring_length"] for o in sumo.options] == [228, 245, 262]
        np.testing.assert_allclose(fast.baseline, sumo.baseline, rtol=0, atol=1e-9)
        ours, theirs = fast.run(feedback_policy, None), sumo.run(feedback_policy, None)
        assert ours is not None and theirs is not None
        for a, b in zip(ours, theirs, strict=True):
            assert a.length == b.length == 400
            assert a.last_half_speed == pytest.approx(b.last_half_speed, abs=1e-9)
            assert a.episode_return == pytest.approx(b.episode_return, abs=1e-7)
        assert fast.score(ours) == pytest.approx(sumo.score(theirs), abs=1e-9)
        assert 0 < fast.score(ours) < 1  # this policy is worse than the humans on some ring
    finally:
        sumo.close()
        fast.close()


def test_a_normalised_policy_sees_the_same_observations_as_on_sumo() -> None:
    cfg = load_config(RING, SHORT)
    seen: list[np.ndarray] = []

    def normalize(obs: np.ndarray) -> np.ndarray:
        seen.append(np.array(obs))
        return (obs - 0.5) * 2

    runner = NumpyEpisodeRunner(cfg, [3, 4])
    scores = runner.run(feedback_policy, normalize)
    assert scores is not None and len(seen) == 400
    assert seen[0].shape == (2, 3) and seen[0].dtype == np.float32
    assert runner.run(feedback_policy, normalize) == scores  # same seeds, same episodes


def test_stop_request_gives_up_the_evaluation() -> None:
    calls = [0]

    def stop() -> bool:
        calls[0] += 1
        return calls[0] > 500  # lets the baseline (400 steps) finish, then 100 more

    runner = NumpyEpisodeRunner(load_config(RING, SHORT), [1], stop)
    assert runner.run(feedback_policy, None) is None
    # asked to stop during the all-human baseline: one unknown baseline per seed
    stopped = NumpyEpisodeRunner(load_config(RING, SHORT), [1, 2], lambda: True)
    assert len(stopped.baseline) == 2 and all(np.isnan(stopped.baseline))


def test_without_a_human_group_both_runners_leave_the_baseline_unknown() -> None:
    cfg = load_config(RING, SHORT)
    only_rl = replace(cfg, vehicles=VehicleParams([g for g in cfg.vehicles.groups if is_rl(g)]))
    fast = NumpyEpisodeRunner(cfg, [1, 2], best_by="return")
    sumo = EpisodeRunner(replace(cfg, env=replace(cfg.env, evaluate=True)), [1, 2], None, "return")
    try:
        for runner in (fast, sumo):
            baseline = runner._baseline(only_rl)  # no human to copy: no episode is played
            assert len(baseline) == 2 and all(np.isnan(baseline))
    finally:
        sumo.close()
        fast.close()


def test_a_config_the_numpy_rings_cannot_run_is_refused_at_eval_backend() -> None:
    cfg = load_config(ROOT / "configs" / "figure_eight_rl.yaml", ["train.eval_backend=numpy"])
    with pytest.raises(ConfigError) as err:
        numpy_eval_plan(cfg)
    assert err.value.path == "train.eval_backend"
    assert "use train.eval_backend: sumo" in err.value.message


def test_cli_refuses_numpy_evaluation_of_a_figure_eight_before_training(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")
    config = tmp_path / "f8.yaml"
    text = (ROOT / "configs" / "figure_eight_rl.yaml").read_text()
    config.write_text(text.replace("train:\n", "train:\n  eval_backend: numpy\n", 1))
    result = CliRunner().invoke(app, ["train", str(config), "--out", str(tmp_path / "runs")])
    assert result.exit_code == 1
    line = 1 + text.splitlines().index("train:") + 1  # the inserted eval_backend line
    assert f"{config}:{line}: train.eval_backend:" in result.output
    assert "numpy evaluation backend" in result.output
    assert not (tmp_path / "runs").exists()  # refused before any work


def test_bad_eval_backend_name_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match="evaluation backend"):
        load_config(RING, ["train.eval_backend=jax"])
