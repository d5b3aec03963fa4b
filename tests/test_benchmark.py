"""Flow's eleven benchmarks as shipped configs: Flow's numbers, the derived baselines, the
names ``flowrun benchmark`` takes, and the results it writes (no SUMO run here)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.model import ExperimentConfig
from flowrun.config.params import is_rl
from flowrun.envs.factory import make_env
from flowrun.errors import ConfigError
from flowrun.experiment.benchmark import BENCHMARKS, default_config_dir, metric_value, select
from flowrun.experiment.benchmark_report import mean_std, notes, write_results
from flowrun.experiment.benchmark_run import BenchmarkPlan, collect
from flowrun.loading.loader import load_config

ROOT = Path(__file__).resolve().parent.parent
BENCH_CONFIGS = ROOT / "configs" / "benchmarks"

#: Flow's numbers (FLOW_FACTS section 1, flow/benchmarks/<name>.py): env class, horizon,
#: sim step, sims per step, warm-up, observation size S, action size A.
FLOW = {
    "figureeight0": ("AccelEnv", 1500, 0.1, 1, 0, 28, 1),
    "figureeight1": ("AccelEnv", 1500, 0.1, 1, 0, 28, 7),
    "figureeight2": ("AccelEnv", 1500, 0.1, 1, 0, 28, 14),
    "merge0": ("MergePOEnv", 750, 0.5, 2, 0, 25, 5),
    "merge1": ("MergePOEnv", 750, 0.5, 2, 0, 65, 13),
    "merge2": ("MergePOEnv", 750, 0.5, 2, 0, 85, 17),
    "grid0": ("TrafficLightGridBenchmarkEnv", 400, 1.0, 1, 0, 339, 9),
    "grid1": ("TrafficLightGridBenchmarkEnv", 400, 1.0, 1, 0, 915, 25),
    "bottleneck0": ("BottleneckDesiredVelocityEnv", 1500, 0.5, 1, 40, 141, 20),
    "bottleneck1": ("BottleneckDesiredVelocityEnv", 1500, 0.5, 1, 40, 141, 20),
    "bottleneck2": ("BottleneckDesiredVelocityEnv", 1500, 0.5, 1, 40, 281, 40),
}


def config(name: str, sets: tuple[str, ...] = ()) -> ExperimentConfig:
    return load_config(BENCH_CONFIGS / f"{name}.yaml", list(sets))


def inflows(cfg: ExperimentConfig) -> list[tuple[str, str, float]]:
    flows = cfg.network.net_params.inflows.get()
    return [(f.edge, f.veh_type, float(f.vehs_per_hour or 0.0)) for f in flows]


def cars(cfg: ExperimentConfig, rl: bool) -> int:
    return sum(g.num_vehicles for g in cfg.vehicles.groups if is_rl(g) == rl)


def test_there_is_one_config_per_benchmark_and_no_other() -> None:
    assert sorted(p.stem for p in BENCH_CONFIGS.glob("*.yaml")) == sorted(BENCHMARKS)
    assert default_config_dir(ROOT) == BENCH_CONFIGS


@pytest.mark.parametrize("name", sorted(FLOW))
def test_config_has_flows_env_horizon_step_and_spaces(name: str) -> None:
    env_class, horizon, step, sims, warmup, n_obs, n_act = FLOW[name]
    cfg = config(name)
    assert cfg.name == name
    assert (cfg.env.env_class, cfg.env.horizon, cfg.sim.sim_step) == (env_class, horizon, step)
    assert (cfg.env.sims_per_step, cfg.env.warmup_steps) == (sims, warmup)
    assert cfg.train is not None and cfg.train.algorithm in ("PPO", "TRPO", "ARS")
    env = make_env(cfg)
    try:
        assert env.observation_space.shape == (n_obs,)
        assert env.action_space.shape == (n_act,)
    finally:
        env.close()


@pytest.mark.parametrize(("name", "humans", "avs"),
                         [("figureeight0", 13, 1), ("figureeight1", 7, 7), ("figureeight2", 0, 14)])
def test_figure_eight_has_flows_humans_and_avs(name: str, humans: int, avs: int) -> None:
    cfg = config(name)
    assert (cars(cfg, rl=False), cars(cfg, rl=True)) == (humans, avs)
    assert cfg.env.additional_params["target_velocity"] == 20
    assert cfg.env.additional_params["max_accel"] == 3


@pytest.mark.parametrize(("name", "share", "num_rl"),
                         [("merge0", 0.1, 5), ("merge1", 0.25, 13), ("merge2", 0.333, 17)])
def test_merge_has_flows_demand_and_av_share(name: str, share: float, num_rl: int) -> None:
    cfg = config(name)
    flows = inflows(cfg)
    highway = {t: v for e, t, v in flows if e == "inflow_highway"}
    assert highway["human"] + highway["rl"] == pytest.approx(2000)
    assert highway["rl"] / 2000 == pytest.approx(share, abs=5e-4)
    assert [(t, v) for e, t, v in flows if e == "inflow_merge"] == [("human", 100)]
    assert cfg.env.additional_params["num_rl"] == num_rl
    assert cfg.network.net_params.additional_params["pre_merge_length"] == 500


@pytest.mark.parametrize(("name", "edges"), [("grid0", 12), ("grid1", 20)])
def test_grid_has_300_veh_per_hour_on_every_entry_edge(name: str, edges: int) -> None:
    flows = inflows(config(name))
    assert len({e for e, _, _ in flows}) == edges
    assert {(t, v) for _, t, v in flows} == {("human", 300.0)}


@pytest.mark.parametrize(("name", "scaling", "rate", "human_lc"),
                         [("bottleneck0", 1, 2500, 0), ("bottleneck1", 1, 2500, 1621),
                          ("bottleneck2", 2, 5000, 0)])  # fmt: skip
def test_bottleneck_has_flows_demand_scaling_and_lane_changes(
    name: str, scaling: int, rate: float, human_lc: int
) -> None:
    cfg = config(name)
    by_type = {t: v for _, t, v in inflows(cfg)}
    assert by_type["human"] + by_type["rl"] == rate
    assert by_type["rl"] / rate == pytest.approx(0.1)
    assert cfg.network.net_params.additional_params["scaling"] == scaling
    assert (cars(cfg, rl=False), cars(cfg, rl=True)) == (scaling, scaling)
    human = next(g for g in cfg.vehicles.groups if not is_rl(g))
    assert human.lane_change_params.lane_change_mode == human_lc


@pytest.mark.parametrize("name", sorted(BENCHMARKS))
def test_baseline_has_no_av_and_evaluates(name: str) -> None:
    bench = BENCHMARKS[name]
    cfg = config(name, bench.baseline)
    assert cfg.env.evaluate is True
    if bench.family == "grid":
        assert cfg.traffic_lights.controller == "actuated"
        return
    assert cars(cfg, rl=True) == 0
    assert all(t != "rl" for _, t, _ in inflows(cfg))
    # the same demand, all human
    total = sum(v for _, _, v in inflows(config(name)))
    assert sum(v for _, _, v in inflows(cfg)) == pytest.approx(total, abs=1)
    if bench.family == "figureeight":
        assert cars(cfg, rl=False) == 14
        group = cfg.vehicles.groups[0]
        # the paper's N(0, 0.2) per 0.1 s step, in flowrun's sqrt(dt)-scaled units
        assert group.acceleration_controller.params["noise"] == pytest.approx(0.2 / 0.1**0.5,
                                                                              abs=1e-3)
        cf = group.car_following_params
        assert cf.speed_mode == 1
        # Flow's 2018 SumoCarFollowingParams() (the paper's commit), minGap 0 under IDM
        assert (cf.accel, cf.decel, cf.min_gap, cf.speed_dev) == (1.0, 1.5, 0.0, 0.1)
        # the same humans as the benchmark configs' own
        assert cf == config("figureeight0").vehicles.groups[0].car_following_params


def test_select_takes_all_families_and_names_in_flows_order() -> None:
    assert [b.name for b in select(["all"])] == list(BENCHMARKS)
    assert [b.name for b in select(["bottleneck", "merge1"])] == [
        "merge1", "bottleneck0", "bottleneck1", "bottleneck2"]  # fmt: skip
    assert [b.name for b in select(["GRID1", "grid1"])] == ["grid1"]


def test_unknown_name_says_did_you_mean() -> None:
    with pytest.raises(ConfigError) as err:
        select(["figureight0"])
    assert "unknown benchmark 'figureight0' (did you mean 'figureeight0'?)" in str(err.value)


def test_cli_unknown_name_is_one_line_and_exit_1(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["benchmark", "mrege0", "--out", str(tmp_path)])
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert len(lines) == 1
    assert "unknown benchmark 'mrege0' (did you mean 'merge0'?)" in lines[0]
    assert not (tmp_path / "benchmark").exists()


def test_cli_bad_set_names_the_benchmark_before_running(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        app, ["benchmark", "merge0", "--set", "env.horizn=5", "--out", str(tmp_path)])
    assert result.exit_code == 1
    assert "benchmark merge0:" in result.output and "horizon" in result.output
    assert not (tmp_path / "benchmark").exists()


def test_help_shares_the_common_option_texts() -> None:
    group = typer.main.get_command(app)
    params = {c: {p.opts[0]: p.help for p in group.commands[c].params  # type: ignore[attr-defined]
                  if p.param_type_name == "option"} for c in ("benchmark", "baseline", "sweep")}
    for flag in ("--set", "--seed"):
        assert params["benchmark"][flag] == params["baseline"][flag]
    # --out names a folder on both, each saying what it receives there
    assert params["benchmark"]["--out"].split(",")[0] != params["baseline"]["--out"].split(",")[0]
    assert "OUT/benchmark/<timestamp>/" in params["benchmark"]["--out"]
    assert params["benchmark"]["--seeds"] == "Seeds per benchmark."
    for flag in ("--seeds", "--jobs", "--train", "--configs", "--record"):
        assert params["benchmark"][flag]


def test_first_seed_is_sim_seed_of_the_config_after_set() -> None:
    from flowrun.cli.commands_benchmark import _first_seed

    assert _first_seed(BENCHMARKS["merge0"], BENCH_CONFIGS, ()) == 0
    assert _first_seed(BENCHMARKS["merge0"], BENCH_CONFIGS, ("sim.seed=7",)) == 7


def test_cli_missing_config_folder_names_the_file(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        app, ["benchmark", "grid1", "--configs", str(tmp_path), "--out", str(tmp_path / "o")])
    assert result.exit_code == 1
    assert f"benchmark grid1: no config {tmp_path.resolve() / 'grid1.yaml'}" in result.output


def test_metric_values_come_from_the_familys_key() -> None:
    row = {"mean_speed": 4.5, "episode_return": -120.0, "outflow": 1100.0}
    assert metric_value(BENCHMARKS["merge0"].metric, row) == 4.5
    assert metric_value(BENCHMARKS["grid0"].metric, row) == -120.0
    assert metric_value(BENCHMARKS["bottleneck0"].metric, row) == 1100.0
    assert metric_value(BENCHMARKS["bottleneck0"].metric, row, policy=True) == -120.0
    assert metric_value(BENCHMARKS["merge0"].metric, {"mean_speed": None}) is None
    assert metric_value(BENCHMARKS["merge0"].metric, {"mean_speed": float("nan")}) is None


def _fake_run(folder: Path, value: dict[str, Any]) -> None:
    folder.mkdir(parents=True)
    (folder / "metrics.json").write_text(json.dumps({"runs": [value]}))
    (folder / "status.json").write_text(json.dumps({"status": "complete"}))


def test_results_hold_mean_and_std_over_seeds_and_missing_runs(tmp_path: Path) -> None:
    plan = BenchmarkPlan(tmp_path, (BENCHMARKS["merge0"], BENCHMARKS["grid0"]), (0, 1, 2),
                         BENCH_CONFIGS)  # fmt: skip
    _fake_run(tmp_path / "baseline" / "merge0" / "seed=0", {"mean_speed": 10.0})
    _fake_run(tmp_path / "baseline" / "merge0" / "seed=1", {"mean_speed": 12.0})
    rows = collect(plan)
    merge, grid = rows
    assert merge["baseline"]["values"] == [10.0, 12.0]
    assert (merge["baseline"]["mean"], merge["baseline"]["std"]) == (11.0, 1.0)
    assert [r["status"] for r in merge["baseline"]["runs"]] == ["complete", "complete", "missing"]
    assert grid["baseline"]["mean"] is None and grid["reference"] is None
    assert mean_std(merge["baseline"]) == "11 ± 1 (n=2)"
    assert notes(rows)[0].startswith("* grid0: Flow's flow/benchmarks/create_movies.sh")
    json_path, md_path, plot = write_results(plan, rows, ["flowrun", "benchmark"], "interrupted")
    data = json.loads(json_path.read_text())
    assert data["status"] == "interrupted" and data["seeds"] == [0, 1, 2]
    assert [r["benchmark"] for r in data["benchmarks"]] == ["merge0", "grid0"]
    assert "| merge0 | mean speed (m/s) | 11 ± 1 (n=2) | 13 |" in md_path.read_text()
    assert plot is not None and plot.stat().st_size > 0
