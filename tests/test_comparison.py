"""Which baseline a policy is compared with (:mod:`flowrun.training.comparison`): a benchmark's
own, built exactly as ``flowrun benchmark`` builds it, else the all-human config."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from rich.console import Console

from flowrun.cli.tables import compare_table
from flowrun.config.params import is_rl
from flowrun.errors import ConfigError
from flowrun.experiment.benchmark import BENCHMARKS
from flowrun.loading.loader import load_config
from flowrun.training.comparison import all_human, comparison_baseline

ROOT = Path(__file__).resolve().parents[1]
BENCH_CONFIGS = ROOT / "configs" / "benchmarks"


def text_of(table: object) -> list[str]:
    console = Console(width=80, record=True, file=io.StringIO())
    console.print(table)
    return console.export_text().splitlines()


@pytest.mark.parametrize("name", list(BENCHMARKS))
def test_a_benchmarks_baseline_is_the_one_flowrun_benchmark_runs(name: str) -> None:
    path = BENCH_CONFIGS / f"{name}.yaml"
    sets = ["env.horizon=50", "sim.seed=7"]  # the user's --set values come first
    compared = comparison_baseline(load_config(path, sets))
    assert compared is not None
    assert (compared.kind, compared.label, compared.benchmark) == ("benchmark", "baseline", name)
    assert compared.config == load_config(path, [*sets, *BENCHMARKS[name].baseline])
    assert compared.config.env.horizon == 50 and compared.config.env.evaluate


def test_figureeight2_every_car_rl_still_has_its_benchmarks_baseline() -> None:
    cfg = load_config(BENCH_CONFIGS / "figureeight2.yaml")
    assert all(is_rl(g) for g in cfg.vehicles.groups)
    compared = comparison_baseline(cfg)
    assert compared is not None
    (humans,) = compared.config.vehicles.groups
    assert humans.num_vehicles == 14 and not is_rl(humans)
    assert compared.description == (
        "the benchmark's own baseline (figureeight2: 14 human drivers of the paper's "
        "vehicle type, no AV)"
    )


def test_other_configs_are_compared_with_their_all_human_version() -> None:
    cfg = load_config(ROOT / "configs" / "ring_wave.yaml")
    compared = comparison_baseline(cfg)
    assert compared is not None
    assert (compared.kind, compared.label, compared.benchmark) == ("all-human", "all-human", None)
    assert compared.config == all_human(cfg)
    only_avs = ("vehicles=[{id: rl, count: 4, acceleration_controller: {type: RLController}, "
                "routing_controller: {type: ContinuousRouter}}]")
    every_rl = load_config(ROOT / "configs" / "ring_wave.yaml", [only_avs])
    assert comparison_baseline(every_rl) is None  # no human to copy: no baseline


def test_a_config_named_like_a_benchmark_that_its_baseline_does_not_fit_is_one_error() -> None:
    # the bottleneck baseline switches off vehicle group 1 (the AVs): a one-group bottleneck
    # config named bottleneck0 has none
    cfg = load_config(ROOT / "configs" / "bottleneck.yaml", ["name=bottleneck0"])
    with pytest.raises(ConfigError) as err:
        comparison_baseline(cfg)
    text = str(err.value)
    assert text.startswith("--set: vehicles[1]: this config is named bottleneck0")
    assert "--set 'vehicles.1.count=0'" in text and "index 1 is out of range" in text
    assert "rename the config (name:)" in text


def test_a_config_named_like_a_benchmark_on_another_network_is_one_error(tmp_path: Path) -> None:
    # the figure eight's baseline overrides (14 humans, evaluate mode) would fit a ring: the
    # network type decides, so a ring named figureeight0 is never compared with the figure eight
    text = (ROOT / "configs" / "ring_wave.yaml").read_text(encoding="utf-8")
    path = tmp_path / "ring.yaml"
    path.write_text(text.replace("name: ring_wave", "name: figureeight0"), encoding="utf-8")
    line = 1 + [ln.strip() for ln in text.splitlines()].index("type: ring")
    with pytest.raises(ConfigError) as err:
        comparison_baseline(load_config(path))
    assert str(err.value).startswith(f"{path}:{line}: network.type: this config is named "
                                     "figureeight0, but its network is 'ring', not the "
                                     "benchmark's 'figure_eight'")
    assert "rename the config (name:)" in str(err.value)


def test_compare_table_shows_a_benchmark_baselines_return() -> None:
    row = {"run": 0, "mean_speed": 5.0, "last_half_mean_speed": 5.0, "speed_std": 1.0,
           "last_half_speed_std": 1.0, "min_speed": 0.0, "episode_return": -204.46,
           "collisions": 0}  # fmt: skip
    lines = text_of(compare_table("t", [row], [row], "baseline"))
    baseline = next(line.split() for line in lines if line.split()[:1] == ["baseline"])
    assert baseline[7] == "-204.5"
    lines = text_of(compare_table("t", [row], [row]))
    human = next(line.split() for line in lines if line.split()[:1] == ["all-human"])
    assert human[7] == "n/a"
