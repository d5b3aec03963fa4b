"""``flowrun eval`` compares a benchmark's policy with the benchmark's own baseline (the one
``flowrun benchmark`` and the README's results table use), any other config's policy with its
all-human version. Real SUMO, the shipped policies, short horizons."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.model import ExperimentConfig
from flowrun.experiment.benchmark import BENCHMARKS
from flowrun.loading.loader import load_config
from flowrun.recording.reader import open_log

pytestmark = [pytest.mark.sumo, pytest.mark.train]
pytest.importorskip("stable_baselines3")

ROOT = Path(__file__).resolve().parents[1]
POLICIES = ROOT / "policies"
BENCH_CONFIGS = ROOT / "configs" / "benchmarks"
SEED, STEPS = 1000000, 60
runner = CliRunner()


def _sets(items: list[str] | tuple[str, ...]) -> list[str]:
    return [arg for item in items for arg in ("--set", item)]


def _eval(name: str, out: Path) -> tuple[dict[str, Any], Path, str]:
    """``flowrun eval policies/<name>`` on one short episode: metrics.json, its folder, and
    the printed output."""
    args = ["eval", str(POLICIES / name), "--episodes", "1", "--seed", str(SEED),
            "--set", "env.evaluate=true", "--set", f"env.horizon={STEPS}", "--out", str(out)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    (folder,) = out.iterdir()
    return json.loads((folder / "metrics.json").read_text()), folder, result.output


def _benchmark_baseline(name: str, out: Path) -> dict[str, Any]:
    """The run row of ``flowrun baseline`` on the benchmark's baseline config (as ``flowrun
    benchmark`` builds it), same seed and steps."""
    cmd = ["baseline", str(BENCH_CONFIGS / f"{name}.yaml"),
           *_sets([*BENCHMARKS[name].baseline, f"env.horizon={STEPS}"]),
           "--seed", str(SEED), "--runs", "1", "--no-record", "--out", str(out)]  # fmt: skip
    result = runner.invoke(app, cmd)
    assert result.exit_code == 0, result.output
    (metrics,) = out.glob("*/*/metrics.json")
    row: dict[str, Any] = json.loads(metrics.read_text())["runs"][0]
    return row


def _attached_config(log: Any, tmp_path: Path) -> ExperimentConfig:
    """The config a log was recorded with (its ``config.yaml`` attachment)."""
    path = tmp_path / "attached.yaml"
    path.write_bytes(log.attachments["config.yaml"])
    return load_config(path)


def _replayed_return(log: Path) -> str:
    """The return ``flowrun replay LOG`` prints."""
    result = runner.invoke(app, ["replay", str(log)])
    assert result.exit_code == 0, result.output
    line = next(line for line in result.output.splitlines() if " return " in line)
    return line.strip("│ ").split()[-1]


def _table_row(output: str, label: str) -> list[str]:
    return next(line.split() for line in output.splitlines() if line.split()[:1] == [label])


def test_figureeight0_is_compared_with_14_human_drivers_of_the_papers_type(
    tmp_path: Path,
) -> None:
    metrics, folder, output = _eval("figureeight0", tmp_path / "eval")
    assert metrics["baseline_kind"] == "benchmark"
    assert "figureeight0: 14 human drivers" in metrics["baseline_description"]
    log = open_log(folder / "baseline_0.mcap")
    frames = list(log.frames())
    assert all(len(f.ids) == 14 and not np.any(f.is_rl) for f in frames)
    assert {t for f in frames for t in f.types} == {"human"}
    (humans,) = _attached_config(log, tmp_path).vehicles.groups  # the rollout's own config
    cf = humans.car_following_params  # the paper's vehicle type
    paper = (14, 1.0, 1.5, 0, 0.1)
    assert (humans.num_vehicles, cf.accel, cf.decel, cf.min_gap, cf.speed_dev) == paper
    assert log.metadata["baseline_kind"] == "benchmark"

    row = _benchmark_baseline("figureeight0", tmp_path / "baseline")
    (ours,) = metrics["baseline"]
    assert ours["steps"] == row["steps"]
    assert ours["mean_speed"] == pytest.approx(row["mean_speed"], abs=1e-12)
    assert "baseline row: the benchmark's own baseline (figureeight0: 14 human" in output
    assert _table_row(output, "baseline")[2] == f"{row['mean_speed']:.3f}"


def test_grid0_is_compared_with_actuated_lights_and_shows_their_minus_delay(
    tmp_path: Path,
) -> None:
    metrics, folder, output = _eval("grid0", tmp_path / "eval")
    assert metrics["baseline_kind"] == "benchmark"
    assert "SUMO's actuated lights" in metrics["baseline_description"]
    (ours,) = metrics["baseline"]
    assert math.isfinite(ours["episode_return"]) and ours["episode_return"] < 0
    row = _benchmark_baseline("grid0", tmp_path / "baseline")
    assert ours["episode_return"] == pytest.approx(row["episode_return"], abs=1e-9)
    assert metrics["baseline_mean"]["episode_return"] == ours["episode_return"]
    assert _table_row(output, "baseline")[7] == f"{row['episode_return']:.1f}"  # not n/a
    attached = _attached_config(open_log(folder / "baseline_0.mcap"), tmp_path)
    assert attached.traffic_lights.controller == "actuated"
    assert _replayed_return(folder / "baseline_0.mcap") == f"{row['episode_return']:.3f}"


def test_a_config_that_is_no_benchmark_keeps_the_all_human_rollout(tmp_path: Path) -> None:
    from flowrun.training.evaluate import all_human, run_evaluation

    cfg = load_config(ROOT / "configs" / "ring_wave.yaml",
                      ["env.horizon=40", "env.warmup_steps=0", "sim.seed=3"])  # fmt: skip
    result = run_evaluation(cfg, tmp_path, tmp_path / "final_model.zip", "complete", {},
                            lambda obs: np.zeros(1), 1, None, tmp_path / "eval")  # fmt: skip
    metrics = json.loads((result.out_dir / "metrics.json").read_text())
    assert metrics["baseline_kind"] == "all-human"
    log = open_log(result.out_dir / "baseline_0.mcap")
    assert _attached_config(log, tmp_path) == all_human(cfg)  # the AV driven like the humans
    assert {t for f in log.frames() for t in f.types} == {"human", "rl"}  # the groups' names
    assert not any(np.any(f.is_rl) for f in log.frames())
    assert log.metadata["baseline_kind"] == "all-human"
    assert _replayed_return(result.out_dir / "baseline_0.mcap") == "n/a"


def test_evaluations_during_training_rank_figureeight2_against_its_benchmarks_baseline() -> None:
    from flowrun.envs.factory import make_env
    from flowrun.training.periodic_eval import EpisodeRunner, play_episode

    path, sets = BENCH_CONFIGS / "figureeight2.yaml", [f"env.horizon={STEPS}"]
    runner_ = EpisodeRunner(load_config(path, sets), [SEED], best_by="speed_ratio")
    runner_.close()  # every car of figureeight2 is an AV
    env = make_env(load_config(path, [*sets, *BENCHMARKS["figureeight2"].baseline]))
    try:
        humans = play_episode(env, SEED, None, None)
    finally:
        env.close()
    assert humans is not None and humans.last_half_speed > 0
    assert runner_.baseline == [humans.last_half_speed]  # was nan: no human group to copy
