"""Signal baselines through ``flowrun baseline``: the controller chosen in YAML, the signal
metrics in the run table and metrics.json (real SUMO, short and seeded)."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.model import ExperimentConfig
from flowrun.config.params import InFlows, NetParams
from flowrun.experiment.baseline import run_baseline
from flowrun.experiment.signal_baselines import run_signal_baseline
from flowrun.loading.loader import load_config

ROOT = Path(__file__).resolve().parents[1]
GRID0 = ROOT / "configs" / "grid0.yaml"
STEPS = 300
SIGNAL_KEYS = ("mean_delay", "mean_travel_time", "throughput", "mean_queue", "waiting_at_end")


def grid0_random_arrivals(controller: str, seed: int) -> ExperimentConfig:
    """configs/grid0.yaml with its controller, and Bernoulli arrivals of the same mean rate
    (300 veh/h per entry edge), so seeds differ."""
    cfg = load_config(GRID0, [f"traffic_lights.controller={controller}", f"sim.seed={seed}"])
    inflows = InFlows()
    for flow in cfg.network.net_params.inflows.get():  # type: ignore[union-attr]
        inflows.add(flow.edge, flow.veh_type, probability=float(flow.vehs_per_hour or 0) / 3600.0,
                    depart_lane="free", depart_speed=flow.depart_speed)  # fmt: skip
    np_ = cfg.network.net_params
    net = replace(cfg.network, net_params=NetParams(np_.additional_params, inflows=inflows))
    return replace(cfg, network=net)


@pytest.mark.sumo
@pytest.mark.parametrize("seed", [0, 1])
def test_actuated_and_max_pressure_beat_fixed_time_in_flowrun_baseline(
    tmp_path: Path, seed: int
) -> None:
    delay = {}
    for controller in ("fixed_time", "actuated", "max_pressure"):
        cfg = grid0_random_arrivals(controller, seed)
        result = run_baseline(cfg, steps=STEPS, out=tmp_path, record=controller == "max_pressure")
        data = json.loads((result.run_dir / "metrics.json").read_text())
        assert data["signal_controller"] == controller
        (run,) = data["runs"]
        assert all(key in run for key in SIGNAL_KEYS)
        assert run["throughput"] > 0 and run["mean_travel_time"] > 0
        delay[controller] = run["mean_delay"]
        if controller == "max_pressure":
            assert [p.name for p in result.logs] == ["run_0.mcap"]
            assert (result.run_dir / "run_0.mcap").stat().st_size > 0
    assert delay["actuated"] < delay["fixed_time"]
    assert delay["max_pressure"] < delay["fixed_time"]


@pytest.mark.sumo
@pytest.mark.parametrize("controller", ["fixed_time", "max_pressure"])
def test_baseline_path_measures_what_run_signal_baseline_measures(
    tmp_path: Path, controller: str
) -> None:
    """The env's own (no-op) actions leave the lights to the controller: same numbers."""
    cfg = grid0_random_arrivals(controller, 3)
    result = run_baseline(cfg, steps=150, out=tmp_path, record=False)
    direct = run_signal_baseline(cfg, controller, 3, steps=150)
    assert result.signals == [direct]


@pytest.mark.sumo
def test_cli_prints_the_signal_table(tmp_path: Path) -> None:
    out = CliRunner().invoke(app, [
        "baseline", str(GRID0), "--steps", "60", "--no-record", "--out", str(tmp_path),
        "--set", "traffic_lights.controller=max_pressure"])  # fmt: skip
    assert out.exit_code == 0, out.output
    assert "signal control: max_pressure" in out.output
    assert "veh/h" in out.output


def test_unknown_controller_is_one_line_and_exit_1(tmp_path: Path) -> None:
    out = CliRunner().invoke(app, [
        "baseline", str(GRID0), "--steps", "5", "--out", str(tmp_path),
        "--set", "traffic_lights.controller=maxpressure"])  # fmt: skip
    assert out.exit_code == 1
    assert "did you mean 'max_pressure'" in out.output


def test_signal_table_shows_n_a_for_what_could_not_be_measured() -> None:
    from types import SimpleNamespace

    from rich.console import Console

    from flowrun.cli.commands_run import signals_table

    row = SimpleNamespace(mean_delay=3.5, mean_travel_time=math.nan, throughput=0.0,
                          mean_queue=0.0, waiting_at_end=0)  # fmt: skip
    console = Console(width=120, record=True)
    console.print(signals_table("t", [row]))
    text = console.export_text()
    assert "nan" not in text
    assert text.splitlines()[3].split() == ["0", "3.5", "n/a", "0", "0.00", "0"]
