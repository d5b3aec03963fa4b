"""``flowrun train`` announces its phases in order and ends with the closing line and the
total wall time (real short training on numpy rings, evaluation on SUMO)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app

pytest.importorskip("stable_baselines3")


@pytest.mark.train
@pytest.mark.sumo
def test_train_announces_phases_and_closes_last(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, [
        "train", "configs/ring_wave_numpy.yaml", "--out", str(tmp_path), "--seed", "0",
        "--set", "train.total_timesteps=500", "--set", "train.eval_freq=0",
        "--set", "train.eval_episodes=1", "--set", "env.horizon=60",
        "--set", "env.warmup_steps=10",
    ])  # fmt: skip
    assert result.exit_code == 0, result.output
    lines = [line for line in result.stdout.splitlines() if line.strip()]
    starts = [i for i, line in enumerate(lines) if line.startswith((
        "starting ", "training for ", "training finished: ", "final evaluation: "))]
    assert [lines[i].split()[0] for i in starts] == ["starting", "training", "training", "final"]
    assert "numpy rings" in lines[starts[0]]
    assert starts == sorted(starts)
    assert lines[-1].startswith("run folder: ")  # the closing line is last, on one line
    assert re.search(r"; evaluation folder: \S+ \(total [0-9.]+ s\)$", lines[-1])
