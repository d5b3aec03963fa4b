"""``flowrun benchmark`` end to end on real SUMO: all eleven baselines at a short horizon, and
one ``--train`` run whose trained policy gets a score."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
import yaml
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.experiment.benchmark import BENCHMARKS


def run(args: list[str]) -> Any:
    result = CliRunner().invoke(app, ["benchmark", *args], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    return result


def results(out: Path) -> dict[str, Any]:
    (folder,) = (out / "benchmark").iterdir()
    data: dict[str, Any] = json.loads((folder / "results.json").read_text())
    data["folder"] = folder
    return data


@pytest.mark.sumo
def test_all_benchmarks_run_their_baselines_and_give_one_finite_row_each(tmp_path: Path) -> None:
    result = run(["all", "--seeds", "1", "--set", "env.horizon=5", "--jobs", "2",
                  "--out", str(tmp_path)])  # fmt: skip
    data = results(tmp_path)
    rows = {r["benchmark"]: r for r in data["benchmarks"]}
    assert list(rows) == list(BENCHMARKS)
    assert data["status"] == "complete" and data["sets"] == ["env.horizon=5"]
    for name, row in rows.items():
        (value,) = row["baseline"]["values"]
        assert math.isfinite(value), name
        assert row["baseline"]["std"] == 0.0
        assert name in result.output
    # the figure eights share one baseline (14 humans), and so do the merges: same seed, same value
    assert len({rows[f"figureeight{i}"]["baseline"]["mean"] for i in range(3)}) == 1
    assert len({rows[f"merge{i}"]["baseline"]["mean"] for i in range(3)}) == 1
    assert rows["grid0"]["baseline"]["mean"] < 0  # -delay
    # the baseline run really is the derived one: evaluate mode, no AV left
    folder = data["folder"] / rows["bottleneck2"]["baseline"]["runs"][0]["folder"]
    saved = yaml.safe_load((folder / "config.yaml").read_text())
    assert saved["env"]["evaluate"] is True
    assert [f["veh_type"] for f in saved["network"]["inflows"]] == ["human"]
    # a policy is scored on the evaluate-mode return: for the bottleneck it is the outflow
    metrics = json.loads((folder / "metrics.json").read_text())["runs"][0]
    assert metrics["episode_return"] == pytest.approx(metrics["outflow"])
    assert (data["folder"] / "results.md").read_text().count("| bottleneck") == 3
    assert (data["folder"] / "benchmark.png").is_file()


@pytest.mark.sumo
@pytest.mark.train
def test_train_adds_the_trained_policys_score(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")
    tiny = ["env.horizon=10", "train.total_timesteps=20", "train.n_envs=1",
            "train.hyperparams.n_delta=1", "train.hyperparams.n_top=1",
            "train.eval_freq=0", "train.checkpoint_freq=0", "train.eval_episodes=1"]  # fmt: skip
    sets = [arg for item in tiny for arg in ("--set", item)]
    result = run(["figureeight0", "--train", "--seeds", "1", *sets, "--out", str(tmp_path)])
    assert "policy (mean ± std)" in result.output
    data = results(tmp_path)
    (row,) = data["benchmarks"]
    policy = row["policy"]
    assert policy["status"] == "complete" and len(policy["values"]) == 1
    assert all(math.isfinite(v) for v in policy["values"])
    # each training seed's score: the mean over the 5 evaluation episodes (seeds never used
    # in training), in evaluate mode, beside the baseline on the same seeds
    (seed,) = policy["seeds"]
    evaluation = data["folder"] / seed["eval"]
    episodes = json.loads((evaluation / "metrics.json").read_text())["policy"]
    assert seed["episodes"] == [e["mean_speed"] for e in episodes] and len(episodes) == 5
    assert policy["values"] == [pytest.approx(sum(seed["episodes"]) / 5)]
    config = yaml.safe_load((evaluation / "config.yaml").read_text())
    assert config["env"]["evaluate"] is True and config["sim"]["seed"] == 1_000_000
    assert [r["seed"] for r in row["baseline"]["runs"]] == list(range(1_000_000, 1_000_005))
    assert (data["folder"] / seed["train_run"] / "final_model.zip").is_file()
    record = json.loads((data["folder"] / seed["result"]).read_text())
    assert record["benchmark"] == "figureeight0" and record["train_seed"] == 0
    assert record["policy"] == seed["episodes"] and len(record["baseline"]) == 5
