"""Same seed in separate processes: identical vehicle data and byte-identical ``metrics.json``;
another seed with noisy drivers differs. Runs that measure nothing write ``null``, not NaN, and a
horizon under one step is refused, not reported as a finished 0-step run."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.params import VehicleParams
from flowrun.errors import ConfigError
from flowrun.experiment.baseline import run_baseline
from flowrun.loading.loader import load_config
from flowrun.recording.reader import open_log
from flowrun.rundir.folders import is_complete

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parent.parent
SUGIYAMA = ROOT / "configs" / "sugiyama.yaml"
NOISE = ROOT / "configs" / "sugiyama_noise.yaml"
FLOWRUN = Path(sys.executable).parent / "flowrun"


def strict_json(text: str) -> Any:
    def refuse(name: str) -> Any:
        raise AssertionError(f"{name} in metrics.json (not JSON)")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def three_runs(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Noisy Sugiyama, 150 steps, three processes at once: seeds 7, 7 and 8."""
    outs = [tmp_path_factory.mktemp(f"p{i}") for i in range(3)]
    procs = []
    for out, seed in zip(outs, (7, 7, 8), strict=True):
        cmd = [str(FLOWRUN), "baseline", str(NOISE), "--out", str(out), "--steps", "150"]
        cmd += ["--seed", str(seed)]
        procs.append(
            subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        )
    folders = []
    for proc, out in zip(procs, outs, strict=True):
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 0, err
        (folder,) = out.glob("sugiyama_noise/*")
        assert is_complete(folder)
        folders.append(folder)
    return folders


def vehicle_data(folder: Path) -> dict[str, np.ndarray]:
    frames = list(open_log(folder / "run_0.mcap").frames())
    return {
        "speed": np.array([f.speed for f in frames]),
        "position": np.array([f.position for f in frames]),
        "time": np.array([f.time for f in frames]),
    }


def test_same_seed_in_two_processes_gives_the_same_vehicles_and_metrics(
    three_runs: list[Path],
) -> None:
    a, b, _ = three_runs
    da, db = vehicle_data(a), vehicle_data(b)
    for key in da:
        np.testing.assert_array_equal(da[key], db[key])
    text_a, text_b = [(f / "metrics.json").read_text() for f in (a, b)]
    assert text_a == text_b  # byte for byte: no timestamps, paths or pids in it
    assert str(a) not in text_a and str(a.parent) not in text_a
    assert strict_json(text_a)["seed"] == 7


def test_another_seed_with_noise_gives_other_vehicles_and_metrics(three_runs: list[Path]) -> None:
    a, _, c = three_runs
    da, dc = vehicle_data(a), vehicle_data(c)
    assert np.abs(da["speed"][-1] - dc["speed"][-1]).max() > 1e-3
    ma, mc = [strict_json((f / "metrics.json").read_text())["runs"][0] for f in (a, c)]
    assert ma["mean_speed"] != mc["mean_speed"]
    assert ma["steps"] == mc["steps"] == 151


def test_a_run_without_vehicles_writes_null_not_nan(tmp_path: Path) -> None:
    # The loader refuses a config without vehicles; a config built in Python reaches the run.
    cfg = replace(load_config(SUGIYAMA), vehicles=VehicleParams())
    result = run_baseline(cfg, steps=5, out=tmp_path)
    data = strict_json((result.run_dir / "metrics.json").read_text())
    (run,) = data["runs"]
    assert run["steps"] == 6
    for key in ("mean_speed", "speed_std", "min_speed", "max_speed", "last_half_mean_speed"):
        assert run[key] is None, key


@pytest.mark.parametrize("horizon", ["0.5", "0", "2.5", "-3"])
def test_a_horizon_that_is_not_a_whole_number_of_steps_is_refused(
    tmp_path: Path, horizon: str
) -> None:
    out = tmp_path / "runs"
    result = CliRunner().invoke(
        app, ["baseline", str(SUGIYAMA), "--out", str(out), "--set", f"env.horizon={horizon}"]
    )
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "env.horizon" in lines[0], result.stderr
    assert not out.exists()
    cfg = load_config(SUGIYAMA)
    with pytest.raises(ConfigError, match="horizon"):
        run_baseline(replace(cfg, env=replace(cfg.env, horizon=float(horizon))), out=out)
    assert not out.exists()
