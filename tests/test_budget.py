"""``--budget``: the wall-time estimate (pure arithmetic on a probe), the refusal up front, and
training that stops at its deadline as a complete run that says so."""

from __future__ import annotations

import importlib
import json
import time
from dataclasses import replace
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.errors import ConfigError, FlowrunError
from flowrun.experiment.benchmark import BENCHMARKS, default_config_dir
from flowrun.experiment.benchmark_results import make_record, markdown_table
from flowrun.experiment.benchmark_run import BenchmarkPlan, train_command
from flowrun.loading.loader import load_config
from flowrun.preflight.budget import (
    OFF_POLICY_EFFICIENCY,
    STARTUP_S,
    TRAINING_EFFICIENCY,
    Workload,
    estimate,
    parse_deadline,
    plan_budget,
    workload,
)

ROOT = Path(__file__).resolve().parents[1]
FIGURE_EIGHT = ROOT / "configs/benchmarks/figureeight0.yaml"
RING = ROOT / "configs/ring_wave.yaml"
# figureeight0 as an ARS recipe of 1M steps evaluated every 96k steps (2 episodes of 1500)
RECIPE_1M = ["train.total_timesteps=1000000", "train.eval_freq=96000",
             "train.best_by=speed_ratio"]
SMALL = ["env.horizon=200", "env.warmup_steps=0", "train.n_envs=2", "train.algorithm=PPO",
         "train.hyperparams={n_steps: 128, batch_size: 128, n_epochs: 1}",
         "train.policy_kwargs.net_arch=[8]", "train.eval_episodes=1", "train.eval_freq=0",
         "train.checkpoint_freq=0"]  # fmt: skip
runner = CliRunner()


def _set(items: list[str]) -> list[str]:
    return [arg for item in items for arg in ("--set", item)]


def test_estimate_divides_training_by_rate_cores_and_efficiency() -> None:
    work = Workload("x", "PPO", runs=3, n_envs=2, train_steps=3_000_000, eval_steps=100_000,
                    after_steps=50_000)  # fmt: skip
    est = estimate(work, step_rate=2_000.0, cores=2)
    assert est.cores_used == 2  # 6 env processes wanted, 2 cores
    assert TRAINING_EFFICIENCY == 0.65
    assert est.train_s == pytest.approx(3_000_000 / (2_000 * 2 * 0.65))  # 1153.8 s
    assert est.eval_s == pytest.approx(100_000 / (2_000 * 2))  # 3 runs, 2 at once: 25 s
    assert est.after_s == pytest.approx(50_000 / 4_000)
    assert est.startup_s == 2 * STARTUP_S  # 3 runs, 2 at a time: two rounds
    assert est.seconds == pytest.approx(3_000_000 / 2_600 + 25 + 12.5 + 40)
    one = estimate(replace(work, runs=1, n_envs=1), 2_000.0, cores=8)
    assert one.cores_used == 1 and one.train_s == pytest.approx(3_000_000 / 1_300)
    # off-policy algorithms step through SB3's own loop, a gradient step after every step
    sac = estimate(replace(work, algorithm="SAC"), 2_000.0, cores=2)
    assert OFF_POLICY_EFFICIENCY < TRAINING_EFFICIENCY
    assert sac.train_s == pytest.approx(3_000_000 / (2_000 * 2 * OFF_POLICY_EFFICIENCY))
    with pytest.raises(ValueError):
        estimate(work, 0.0, 2)


def test_workload_counts_the_evaluation_episodes() -> None:
    cfg = load_config(FIGURE_EIGHT, RECIPE_1M)
    work = workload(cfg, runs=3, benchmark=True)
    assert work.train_steps == 3_000_000 and work.n_envs == 2 and work.algorithm == "ARS"
    periodic = 3 * (1 + 1_000_000 // 96_000) * 2 * 1500  # the all-human reference, then 10
    assert work.eval_steps == periodic + 5 * 1500  # + the baselines on 5 evaluation seeds
    assert work.after_steps == 3 * 2 * 2 * 1500 + 3 * 2 * 5 * 1500  # final + flowrun eval
    resumed = workload(cfg, runs=1, benchmark=False, done=400_000)
    assert resumed.train_steps == 600_000 and resumed.after_steps == 2 * 2 * 1500
    by_return = workload(load_config(FIGURE_EIGHT, [*RECIPE_1M, "train.best_by=return"]), 1,
                         benchmark=False)  # fmt: skip
    assert by_return.eval_steps == (1_000_000 // 96_000) * 2 * 1500  # no all-human reference


def test_plan_refuses_an_estimate_over_the_budget_and_says_how_to_fit() -> None:
    cfg = load_config(FIGURE_EIGHT, RECIPE_1M)
    work = workload(cfg, runs=1, benchmark=False)

    def probe(_: object) -> float:
        return 5_000.0

    # training 1M / (5000 x 2 x 0.65) = 153.8 s; evaluations (1 + 10 periodic) x 2 x 1500 =
    # 33k steps = 6.6 s, the final one 2 x 2 x 1500 = 1.2 s; start-up 20 s: 181.7 s in all
    est = estimate(work, 5_000.0, 2)
    assert est.seconds == pytest.approx(1_000_000 / 6_500 + 27.8)
    with pytest.raises(FlowrunError) as err:
        plan_budget([(cfg, work)], minutes=2.0, cores=2, probe=probe)
    text = str(err.value)
    assert text.startswith("estimated 3.0 min, over the --budget of 2 min (figureeight0: ")
    assert "1M training steps at 5,000 env steps/s x 2 core(s) x 0.65 (ARS) = 2.6 min" in text
    assert "env steps/s from one episode of one env (at most 3,000 steps)" in text
    # 2 min leave 92.2 s for training: 599k steps, rounded down to two digits
    assert text.endswith("to fit: --set train.total_timesteps=590000 or --budget 4")
    fits = plan_budget([(cfg, work)], minutes=10.0, cores=2, probe=probe, now=1_000.0)
    assert fits.deadline == pytest.approx(1_000.0 + 600 - est.after_s)
    assert "of the 10 min budget" in fits.describe()
    with pytest.raises(ConfigError, match="positive number of minutes"):
        plan_budget([(cfg, work)], minutes=0.0, probe=probe)


def test_deadline_text_is_iso_utc() -> None:
    assert parse_deadline("1970-01-01T00:01:40+00:00") == 100.0
    assert parse_deadline("1970-01-01T00:01:40") == 100.0  # no zone: UTC
    with pytest.raises(ConfigError, match="ISO 8601"):
        parse_deadline("in ten minutes")


def test_benchmark_trainings_get_the_deadline() -> None:
    plan = BenchmarkPlan(Path("/b"), (BENCHMARKS["figureeight0"],), (0,), default_config_dir(),
                         train=True, deadline="2026-11-28T04:00:00+00:00")  # fmt: skip
    cmd = train_command(plan, BENCHMARKS["figureeight0"], 0)
    assert cmd[-2:] == ["--deadline", "2026-11-28T04:00:00+00:00"]
    assert "--deadline" not in train_command(replace(plan, deadline=None), plan.benchmarks[0], 0)


def test_result_file_says_the_training_stopped_at_the_budget() -> None:
    train = {"algorithm": "ARS", "seed": 0, "timesteps": 400_000, "status": "complete",
             "stopped_at_budget": True}  # fmt: skip
    record = make_record(BENCHMARKS["figureeight0"], train, {"total_timesteps": 1_000_000},
                         [6.0], [4.2], ["cmd"])  # fmt: skip
    assert record["stopped_at_budget"] is True
    assert "| 0 (stopped at the budget at 0.4M of 1M steps) |" in markdown_table([record])


@pytest.mark.sumo
def test_a_tiny_budget_is_refused_before_anything_runs(tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = runner.invoke(app, ["benchmark", "figureeight0", "--train", "--budget", "0.01",
                                 *_set(RECIPE_1M), "--out", str(out)])  # fmt: skip
    assert result.exit_code == 1
    assert "error: estimated " in result.stderr and "over the --budget of 0.01 min" in result.stderr
    assert "figureeight0: 1 run(s), 1M training steps at " in result.stderr
    assert "to fit: " in result.stderr and "or --budget " in result.stderr
    assert not list(out.rglob("*"))  # no benchmark folder, no baseline, no training
    result = runner.invoke(app, ["train", str(FIGURE_EIGHT), "--budget", "0.01",
                                 "--out", str(out)])  # fmt: skip
    assert result.exit_code == 1 and "over the --budget of 0.01 min" in result.stderr
    assert not list(out.rglob("*"))


@pytest.mark.sumo
@pytest.mark.train
def test_training_that_fits_says_its_estimate_and_completes(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")
    args = ["train", str(RING), "--budget", "30", "--out", str(tmp_path),
            *_set([*SMALL, "train.total_timesteps=256"])]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "of the 30 min budget (ring_wave: 1 run(s), 256 training steps at " in result.output
    (run,) = (tmp_path / "ring_wave").iterdir()
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["status"] == "complete" and metrics["timesteps"] == 256
    assert metrics["stopped_at_budget"] is False and "budget_deadline" in metrics


@pytest.mark.sumo
@pytest.mark.train
def test_training_stops_at_its_deadline_as_a_complete_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("stable_baselines3")
    trainer = importlib.import_module("flowrun.training.trainer")
    polls = [0]

    def clock(deadline: float | None) -> object:
        """The deadline passes at the 300th look at it (not at a time: the load varies)."""

        def past() -> bool:
            polls[0] += 1
            return polls[0] > 300

        assert deadline is not None
        return past

    monkeypatch.setattr(trainer, "_past", clock)
    when = time.strftime("%Y-%m-%dT%H:%M:%S+00:00", time.gmtime(time.time() + 3600))
    args = ["train", str(RING), "--deadline", when, "--out", str(tmp_path),
            *_set([*SMALL, "train.total_timesteps=10000000"])]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "training stopped at the --budget: " in result.output
    (run,) = (tmp_path / "ring_wave").iterdir()
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["status"] == "complete" and metrics["stopped_at_budget"] is True
    assert 300 <= metrics["timesteps"] <= 2 * 301  # one poll per step of the 2 envs
    assert metrics["budget_deadline"] == when
    assert (run / "final_model.zip").is_file()  # the model at the deadline, evaluated
    assert json.loads(next((run / "eval").glob("*/metrics.json")).read_text())["status"] == (
        "complete"
    )
