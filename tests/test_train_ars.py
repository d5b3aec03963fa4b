"""ARS (sb3-contrib) in ``train:``: real short seeded trainings and the checks of its options."""

from __future__ import annotations

import csv
import json
import zipfile
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app

pytestmark = pytest.mark.train
pytest.importorskip("sb3_contrib")

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "ring_wave.yaml"
# 60-step episodes; 2 directions -> 4 candidates (240 steps) an update, on 2 workers.
ARS = [
    "env.horizon=60",
    "env.warmup_steps=0",
    "train.algorithm=ARS",
    "train.policy=LinearPolicy",
    "train.policy_kwargs={with_bias: true}",
    "train.n_envs=2",
    "train.normalize=true",
    "train.hyperparams={n_delta: 2, n_top: 1, learning_rate: 0.05, delta_std: 0.1}",
    "train.total_timesteps=480",
    "train.eval_freq=0",
    "train.checkpoint_freq=0",
]
runner = CliRunner()


def _train(out: Path, seed: int, extra: tuple[str, ...] = ()) -> Path:
    args = ["train", str(CONFIG), "--seed", str(seed), "--out", str(out)]
    for item in [*ARS, *extra]:
        args += ["--set", item]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    (run,) = list((out / "ring_wave").iterdir())
    return run


def _weights(run: Path) -> list[float]:
    from sb3_contrib import ARS

    with zipfile.ZipFile(run / "final_model.zip") as saved:  # nothing of the live process
        assert "should_stop" not in json.loads(saved.read("data"))
    model = ARS.load(run / "final_model.zip", device="cpu")
    return [float(x) for x in model.weights.cpu().numpy()]


def test_ars_trains_on_two_workers_and_is_reproducible(tmp_path: Path) -> None:
    run = _train(tmp_path / "a", seed=4)
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["status"] == "complete"
    assert metrics["algorithm"] == "ARS"
    assert metrics["timesteps"] == 480  # 2 updates of 4 candidates x 60 steps
    # Every candidate episode ran in a worker: 4 a worker, each in its own Monitor file.
    for rank in (0, 1):
        with open(run / "monitor" / f"env_{rank}.monitor.csv") as f:
            rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
        assert [int(r["l"]) for r in rows] == [60] * 4
    weights = _weights(run)
    assert len(weights) == 2 * 1 * 22 + 1 or any(w != 0 for w in weights)
    assert any(w != 0 for w in weights)  # zero_policy start, then two updates moved it
    # The merged observation statistics are saved with the model (both workers' steps).
    from stable_baselines3.common.vec_env.vec_normalize import VecNormalize

    stats = VecNormalize.load  # the pickle holds obs_rms; read it without an env
    import pickle

    with open(run / "vecnormalize.pkl", "rb") as f:
        normalize = pickle.load(f)
    assert isinstance(normalize, VecNormalize) and stats is not None
    assert normalize.obs_rms.count > 400
    assert normalize.norm_reward is False  # candidates are ranked by raw returns
    # Same seed, same weights.
    assert _weights(_train(tmp_path / "b", seed=4)) == weights
    # The run folder evaluates like any other.
    result = runner.invoke(app, ["eval", str(run), "--episodes", "1"])
    assert result.exit_code == 0, result.output


def test_ars_options_are_checked_before_anything_starts(tmp_path: Path) -> None:
    bad = {
        "train.hyperparams.n_detla=4": ("n_detla", "did you mean 'n_delta'"),
        "train.hyperparams.n_top=3": ("n_top", "must be <= n_delta (2)"),
        "train.hyperparams.delta_std=0": ("delta_std", "must be > 0"),
        "train.hyperparams.zero_policy=1": ("zero_policy", "expected true or false"),
        "train.policy=LinearPolcy": ("train.policy", "did you mean 'LinearPolicy'"),
        "train.policy_kwargs={net_arch: [8]}": ("net_arch", "LinearPolicy takes no argument"),
    }
    for item, (where, message) in bad.items():
        args = ["train", str(CONFIG), "--out", str(tmp_path)]
        for setting in [*ARS, item]:
            args += ["--set", setting]
        result = runner.invoke(app, args)
        assert result.exit_code == 1, item
        assert where in result.output and message in result.output, (item, result.output)
    assert not (tmp_path / "ring_wave").exists()


def test_unknown_algorithm_says_which_exist(tmp_path: Path) -> None:
    result = runner.invoke(app, ["validate", str(CONFIG), "--set", "train.algorithm=ASR"])
    assert result.exit_code == 1
    assert "train.algorithm" in result.output and "ARS" in result.output


def test_common_random_numbers_give_every_candidate_the_updates_episode() -> None:
    from sb3_contrib import ARS as Ars

    from flowrun.loading.loader import load_config
    from flowrun.training.ars import WorkerEnv
    from flowrun.training.numpy_predict import CandidateSeeds, _Candidates
    from flowrun.training.vecenv import EnvFactory

    cfg = load_config(CONFIG, ARS)  # ring lengths drawn at each reset from the env's generator
    spec = WorkerEnv(EnvFactory(cfg), 7, False)
    env = spec.factory()
    try:
        model = Ars("LinearPolicy", env, n_delta=2, n_top=1, device="cpu")
    finally:
        env.close()
    worker = _Candidates(spec, model.policy, 1)
    try:
        weights = model.weights.cpu()
        first = worker.play(weights)  # the worker's seed 7
        moved_on = worker.play(weights)  # its generator continues: another ring
        assert moved_on != first
        worker.seed_each = 20_003
        shared = worker.play(weights)
        assert worker.play(weights) == shared  # the same weights, the same episode
        assert shared != moved_on
    finally:
        worker.env.close()
    seeds = CandidateSeeds(20_000, update=5)  # a resumed run continues its updates' seeds
    assert [seeds.next(), seeds.next()] == [20_005, 20_006]


def test_common_random_numbers_train_reproducibly_and_only_for_ars(tmp_path: Path) -> None:
    crn = ("train.common_random_numbers=true",)
    run = _train(tmp_path / "a", seed=4, extra=crn)
    assert _weights(run) != _weights(_train(tmp_path / "b", seed=4))
    assert _weights(run) == _weights(_train(tmp_path / "c", seed=4, extra=crn))
    result = runner.invoke(app, ["validate", str(CONFIG), "--set",
                                 "train.common_random_numbers=true"])  # fmt: skip
    assert result.exit_code == 1
    assert "train.common_random_numbers" in result.output
    assert "an ARS setting" in result.output and "not one of PPO" in result.output
