"""The commands' tables fit 80 columns, say n/a for what is not defined, and lead with each
network's headline metric; the plain-text progress for output that is not a terminal."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path
from types import SimpleNamespace

import pytest
from rich.console import Console
from typer.testing import CliRunner

from flowrun.cli import feedback as fb
from flowrun.cli.main import app
from flowrun.cli.tables import compare_table, metrics_table, signals_table


def run(**kw: float) -> SimpleNamespace:
    values = dict(run=0, departed=0, arrived=0, duration=300.0, mean_speed=10.774,
                  last_half_mean_speed=7.397, speed_std=5.127, min_speed=0.0,
                  episode_return=133.12, collisions=0, teleports=0)  # fmt: skip
    return SimpleNamespace(**(values | kw))


def text_of(table: object, width: int = 80) -> list[str]:
    console = Console(width=width, record=True, file=io.StringIO())
    console.print(table)
    return console.export_text().splitlines()


def test_open_network_table_leads_with_outflow_and_fits_80_columns() -> None:
    lines = text_of(metrics_table("merge", [run(departed=166, arrived=126)], [1512.4]))
    assert max(len(line) for line in lines) <= 80
    assert "…" not in "".join(lines)
    header = lines[1].split()
    assert header[:2] == ["run", "outflow"]
    assert lines[3].split()[:2] == ["0", "1512"]  # metrics.json's outflow, last 500 s
    assert "last 500 s" in lines[-1]


def test_ring_table_has_no_outflow_and_grid_table_leaves_it_to_the_signals() -> None:
    assert "outflow" not in "".join(text_of(metrics_table("ring", [run()], [0.0])))
    grid = run(departed=10, arrived=8)
    assert "outflow" not in "".join(text_of(metrics_table("grid", [grid])))


def test_undefined_numbers_read_n_a() -> None:
    lines = text_of(metrics_table("empty", [run(mean_speed=math.nan, min_speed=math.nan)]))
    cells = lines[3].split()
    assert cells[1] == "n/a" and cells[4] == "n/a" and "nan" not in "".join(lines)


def test_compare_table_all_human_return_is_n_a_and_fits_80_columns() -> None:
    row = dict(run=0, mean_speed=3.9, last_half_mean_speed=4.3, speed_std=0.9,
               last_half_speed_std=1.0, min_speed=0.0, episode_return=254.2, collisions=0)
    lines = text_of(compare_table("t", [row], [row | {"episode_return": 0.0}]))
    assert max(len(line) for line in lines) <= 80 and "…" not in "".join(lines)
    policy = next(line for line in lines if line.split()[:1] == ["policy"])
    human = next(line for line in lines if line.split()[:1] == ["all-human"])
    assert policy.split()[-2] == "254.2" and human.split()[-2] == "n/a"


def test_signal_table_fits_80_columns() -> None:
    row = SimpleNamespace(mean_delay=32.8, mean_travel_time=72.5, throughput=2016.0,
                          mean_queue=17.84, waiting_at_end=18)  # fmt: skip
    lines = text_of(signals_table("signal control: the network's programs", [row]))
    assert max(len(line) for line in lines) <= 80 and "…" not in "".join(lines)


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_plain_progress_prints_a_line_every_ten_seconds_and_closes_with_the_total() -> None:
    out = io.StringIO()
    clock = Clock()
    feedback = fb.Feedback(Console(file=out, width=80), clock=clock)
    assert not feedback.console.is_terminal
    with feedback.progress((), lambda f: f"run {f['run']}", total=1000, run=0) as update:
        for step in range(0, 1001, 100):
            clock.now = step * 0.025  # 25 s in all
            update(completed=step, run=0)
    clock.now = 26.0
    feedback.close("run folder: x")
    lines = out.getvalue().splitlines()
    assert lines == [
        "run 0: 400/1000 (40 %), 10.0 s",
        "run 0: 800/1000 (80 %), 20.0 s",
        "run folder: x (total 26.0 s)",
    ]


def test_durations_read_naturally() -> None:
    assert fb.duration(12.34) == "12.3 s"
    assert fb.duration(205.6) == "3 min 26 s"
    assert fb.duration(3725) == "1 h 02 min"


@pytest.mark.sumo
def test_baseline_says_what_it_starts_and_counts_steps_after_the_warm_up(tmp_path: Path) -> None:
    config = Path(__file__).resolve().parent.parent / "configs" / "ring_wave.yaml"
    out = tmp_path
    result = CliRunner().invoke(app, ["baseline", str(config), "--steps", "20", "--set",
                                      "env.warmup_steps=30", "--out", str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0] == ("ring_wave: 1 run(s) x 20 steps after 30 warm-up steps; building the "
                        "network and starting SUMO")  # fmt: skip
    assert lines[-1].startswith("run folder: ") and lines[-1].endswith(" s)")
    (metrics,) = out.glob("ring_wave/*/metrics.json")
    data = json.loads(metrics.read_text())
    assert data["steps_per_run"] == 20 and data["runs"][0]["steps"] == 1 + 30 + 20


@pytest.mark.sumo
def test_the_tables_outflow_is_metrics_json_outflow(tmp_path: Path) -> None:
    config = Path(__file__).resolve().parent.parent / "configs" / "merge.yaml"
    result = CliRunner().invoke(app, ["baseline", str(config), "--steps", "200", "--out",
                                      str(tmp_path)])  # fmt: skip
    assert result.exit_code == 0, result.output
    (metrics,) = tmp_path.glob("merge/*/metrics.json")
    outflow = json.loads(metrics.read_text())["runs"][0]["outflow"]
    row = next(line for line in result.stdout.splitlines() if line.split()[:1] == ["0"])
    assert row.split()[1] == f"{outflow:.0f}"
