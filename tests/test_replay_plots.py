"""Plots that cannot mislead: each figure is captured before it is saved and its axes checked."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from flowrun.cli.replay_outputs import PlotKind, draw_plots
from flowrun.experiment.baseline import run_baseline
from flowrun.experiment.benchmark_report import plot_results, plot_title
from flowrun.experiment.benchmark_run import BenchmarkPlan
from flowrun.loading.loader import load_config
from flowrun.recording import McapRecorder, open_log
from flowrun.recording.synthetic import ring_frames
from flowrun.replay import layout_for, plot_speeds, speed_series
from flowrun.replay import plots as plots_mod
from flowrun.replay import signal_plots as signal_mod
from flowrun.replay.signals import signal_series

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
RING_CONFIG = "name: ring\nsim: {step: 0.1}\nenv: {warmup_steps: 50}\n"


@pytest.fixture
def figures(monkeypatch: pytest.MonkeyPatch) -> dict[str, Figure]:
    """Every figure the plot functions save, by file name (nothing is drawn to disk)."""
    saved: dict[str, Figure] = {}

    def keep(fig: Figure, out: Any) -> Path:
        saved[Path(out).name] = fig
        return Path(out)

    monkeypatch.setattr(plots_mod, "_save", keep)
    monkeypatch.setattr(signal_mod, "_save", keep)
    return saved


def _ring_log(path: Path, v_free: float = 6.0, steps: int = 300, jam: bool = False) -> Path:
    """A synthetic ring log; ``jam``: 20 cars stand, 2 drive at ``v_free`` (std > mean)."""
    meta = {"config_name": "ring", "seed": "0", "network_closed": "true", "config": RING_CONFIG}
    with McapRecorder(path, metadata=meta) as rec:
        for frame, stats in ring_frames(22, steps, v_free=v_free, dip=v_free):
            if jam:
                speed = np.zeros(22)
                speed[:2] = v_free
                frame = dataclasses.replace(frame, speed=speed)
            rec.write(frame, stats)
    return path


def _draw(kind: PlotKind, paths: list[Path], tmp: Path, chosen: list[str] | None = None) -> None:
    logs = [open_log(p) for p in paths]
    series = [speed_series(lg, vehicles=chosen) for lg in logs]
    layouts = [layout_for(lg, None) for lg in logs]
    draw_plots(kind, logs, layouts, series, None, None, chosen, tmp, [])


def test_speed_band_never_goes_below_zero(tmp_path, figures):
    log = open_log(_ring_log(tmp_path / "a.mcap", v_free=3.0, jam=True))
    s = speed_series(log)
    assert (s.mean - s.std).min() < 0  # the raw band would
    plot_speeds([log], tmp_path / "speeds.png", series=[s])
    ax = figures["speeds.png"].axes[0]
    bands = [c for c in ax.collections if isinstance(c, PolyCollection)]
    assert bands and min(p.vertices[:, 1].min() for c in bands for p in c.get_paths()) >= 0
    assert ax.get_ylim()[0] == 0


def test_compared_runs_share_colour_scale_and_y_ranges(tmp_path, figures):
    a = _ring_log(tmp_path / "a.mcap", v_free=4.0)
    b = _ring_log(tmp_path / "b.mcap", v_free=9.0)
    _draw(PlotKind.all, [a, b], tmp_path)
    clims = [figures[f"time_space_{k}.png"].axes[0].collections[0].get_clim() for k in "AB"]
    assert clims[0] == clims[1] and clims[0][0] == 0 and clims[0][1] >= 8.9
    ylims = [figures[f"vehicle_speeds_{k}.png"].axes[0].get_ylim() for k in "AB"]
    assert ylims[0] == ylims[1]
    traffic = [figures[f"traffic_{k}.png"].axes[0].get_ylim() for k in "AB"]
    assert traffic[0] == traffic[1]


def test_warm_up_is_shaded_and_labelled(tmp_path, figures):
    _draw(PlotKind.all, [_ring_log(tmp_path / "a.mcap")], tmp_path)
    for name in ("speeds.png", "time_space.png", "vehicle_speeds.png", "traffic.png"):
        ax = figures[name].axes[0]
        labels = [t.get_text() for t in ax.texts]
        assert "warm-up" in labels, name
        spans = [p for p in ax.patches if p.get_x() == 0 and p.get_width() == pytest.approx(5.0)]
        assert spans, name  # 50 steps of 0.1 s


def test_vehicles_filter_names_the_vehicles_in_the_title(tmp_path, figures):
    _draw(PlotKind.speed, [_ring_log(tmp_path / "a.mcap")], tmp_path, ["idm_0", "idm_1"])
    title = figures["speeds.png"].axes[0].get_title()
    assert "vehicles idm_0, idm_1" in title and "all vehicles" not in title


def test_ring_traffic_plot_has_no_flat_density_or_zero_outflow_panel(tmp_path, figures):
    _draw(PlotKind.traffic, [_ring_log(tmp_path / "a.mcap")], tmp_path)
    fig = figures["traffic.png"]
    assert len(fig.axes) == 1 and fig.axes[0].get_ylabel() == "Speed [m/s]"
    assert "closed network" in fig.axes[0].get_xlabel()


@pytest.mark.sumo
def test_merge_vehicle_plot_counts_every_vehicle_of_the_log(tmp_path, figures):
    cfg = load_config(CONFIGS / "merge.yaml")
    path = run_baseline(cfg, steps=60, out=tmp_path / "runs").logs[0]
    every = {v for f in open_log(path).frames() for v in f.ids}
    _draw(PlotKind.all, [path], tmp_path)
    title = figures["vehicle_speeds.png"].axes[0].get_title()
    assert f"of {len(every)} vehicles" in title, title


@pytest.mark.sumo
def test_signal_bands_sit_above_the_queues_not_below_zero(tmp_path, figures):
    cfg = load_config(CONFIGS / "grid0.yaml")
    path = run_baseline(cfg, steps=40, out=tmp_path / "runs").logs[0]
    log = open_log(path)
    signal_mod.plot_signals(log, tmp_path / "signals.png", signal_series(log))
    for ax in figures["signals.png"].axes:
        if not ax.get_visible():
            continue
        assert ax.get_ylim()[0] == 0 and min(ax.get_yticks()) >= 0
        bars = [c for c in ax.collections if c.get_transform() is not ax.transData]
        assert bars  # the bands are drawn in panel coordinates, in the top strip


def test_benchmark_plot_legend_is_outside_the_panels_and_title_names_the_sets(tmp_path):
    from flowrun.experiment.benchmark import BENCHMARKS

    configs = CONFIGS / "benchmarks"
    plan = BenchmarkPlan(tmp_path, (BENCHMARKS["merge0"],), (0,), configs,
                         sets=("env.horizon=100",))  # fmt: skip
    assert "--set env.horizon=100" in plot_title(plan)
    rows = [{"family": "merge", "benchmark": "merge0", "metric": "mean speed", "unit": "m/s",
             "reference": 13.0, "baseline": {"mean": 11.0, "std": 1.0}}]  # fmt: skip
    captured: list[Figure] = []
    original = Figure.savefig

    def keep(self: Figure, *args: Any, **kwargs: Any) -> None:
        captured.append(self)
        original(self, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Figure, "savefig", keep)
        assert plot_results(plan, rows) is not None
    fig = captured[0]
    assert all(ax.get_legend() is None for ax in fig.axes)  # no legend over the bars
    assert fig.legends and "Flow's reference" in [t.get_text() for t in fig.legends[0].texts]
    assert "env.horizon=100" in fig._suptitle.get_text()
    assert np.isfinite(fig.axes[0].get_ylim()).all()
