"""``flowrun replay`` on open roads: positions along a route, traffic, outflow, the CLI.

A synthetic log (no SUMO) drives cars along ``a → (junction) → b`` and one car in from the ramp
``r``; a real short merge log (``configs/merge.yaml``) goes through the CLI.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from flowrun.cli.commands_replay import register
from flowrun.errors import RecordingError
from flowrun.experiment.baseline import run_baseline
from flowrun.recording import McapLog, McapRecorder, StepStats, VehicleFrame, open_log
from flowrun.recording.synthetic import step_stats
from flowrun.replay import (
    NetTopology,
    layout_for,
    outflow,
    route_layout,
    summarize,
    time_space_points,
    traffic_series,
)
from tests.conftest import load

# a (100 m) -> :j_0 (10 m) -> :j_2 (3 m, an internal junction) -> b (200 m); r (50 m) ->
# :j_1 (12 m) -> b.
NET = b"""<?xml version="1.0" encoding="UTF-8"?>
<net version="1.20">
  <edge id=":j_0" function="internal"><lane id=":j_0_0" index="0" length="10.00"/></edge>
  <edge id=":j_1" function="internal"><lane id=":j_1_0" index="0" length="12.00"/></edge>
  <edge id=":j_2" function="internal"><lane id=":j_2_0" index="0" length="3.00"/></edge>
  <edge id="a" from="n" to="j"><lane id="a_0" index="0" length="100.00"/></edge>
  <edge id="r" from="m" to="j"><lane id="r_0" index="0" length="50.00"/></edge>
  <edge id="b" from="j" to="e"><lane id="b_0" index="0" length="200.00"/></edge>
  <connection from="a" to="b" fromLane="0" toLane="0" via=":j_0_0" dir="s" state="M"/>
  <connection from="r" to="b" fromLane="0" toLane="0" via=":j_1_0" dir="s" state="m"/>
  <connection from=":j_0" to="b" fromLane="0" toLane="0" via=":j_2_0" dir="s" state="M"/>
  <connection from=":j_2" to="b" fromLane="0" toLane="0" dir="s" state="M"/>
  <connection from=":j_1" to="b" fromLane="0" toLane="0" dir="s" state="M"/>
</net>
"""
Lanes = tuple[tuple[str, float], ...]  # (edge, length) in driving order
MAIN: Lanes = (("a", 100.0), (":j_0", 10.0), (":j_2", 3.0), ("b", 200.0))
RAMP: Lanes = (("r", 50.0), (":j_1", 12.0), ("b", 200.0))
DT = 0.5


def _place(path: Lanes, s: float) -> tuple[str, float] | None:
    """Edge and lane position at distance ``s`` along a path (``None``: past its end)."""
    for edge, length in path:
        if s < length:
            return edge, s
        s -= length
    return None


def _synthetic_log(path: Path, steps: int = 300) -> dict[str, list[tuple[float, float]]]:
    """Main-road cars enter every 8 s at 0 m and 10 m/s; one ramp car at 5 s, 8 m/s.

    Returns every car's (time, distance along its own path) while in the network.
    """
    cars = {f"m{k}": (8.0 * k, 10.0, MAIN) for k in range(12)}
    cars["ramp"] = (5.0, 8.0, RAMP)
    truth: dict[str, list[tuple[float, float]]] = defaultdict(list)
    alive: set[str] = set()
    meta = {"config_name": "toy", "main_route": json.dumps(["a", "b"]), "network_closed": "false"}
    with McapRecorder(path, metadata=meta, attachments={"network.net.xml": NET}) as rec:
        for step in range(steps):
            t = step * DT
            ids, edges, lane_pos, speed = [], [], [], []
            for vid, (t0, v, route) in cars.items():
                if t < t0:
                    continue
                where = _place(route, v * (t - t0))
                if where is None:
                    continue
                ids.append(vid)
                edges.append(where[0])
                lane_pos.append(where[1])
                speed.append(v)
                truth[vid].append((t, v * (t - t0)))
            departed, arrived = len(set(ids) - alive), len(alive - set(ids))
            alive = set(ids)
            n = len(ids)
            z = np.zeros(n)
            frame = VehicleFrame(
                step, t, ids, ["human"] * n, edges, np.zeros(n, dtype=np.int64),
                np.array(lane_pos), z, z, z, z, np.array(speed), z, z, np.full(n, np.inf),
                [""] * n, np.zeros(n, dtype=bool),
            )  # fmt: skip
            stats = step_stats(frame)
            stats.departed, stats.arrived = departed, arrived
            rec.write(frame, stats)
    return truth


@pytest.fixture
def toy(tmp_path: Path) -> tuple[McapLog, dict[str, list[tuple[float, float]]]]:
    truth = _synthetic_log(tmp_path / "toy.mcap")
    return open_log(tmp_path / "toy.mcap"), truth


def test_a_route_is_laid_out_through_its_junction() -> None:
    layout = route_layout(NetTopology.parse(NET), ["a", "b"])
    assert layout.offsets == {"a": 0.0, ":j_0": 100.0, ":j_2": 110.0, "b": 113.0}
    assert layout.length == 313.0
    ramp = route_layout(NetTopology.parse(NET), ["r", "b"])
    assert ramp.offsets == {"r": 0.0, ":j_1": 50.0, "b": 62.0}


def test_the_diagram_has_only_cars_on_the_route_at_their_distance_along_it(
    toy: tuple[McapLog, dict[str, list[tuple[float, float]]]],
) -> None:
    log, truth = toy
    layout = layout_for(log)
    assert layout is not None and layout.edges == ("a", "b")
    ts = time_space_points(log, route=layout)
    assert ts.times.size > 100
    for vid in set(ts.ids.tolist()):
        sel = ts.ids == vid
        t, pos = ts.times[sel], ts.positions[sel]
        assert np.all(np.diff(t) > 0) and np.all(np.diff(pos) > 0)  # forward along the route
        expected = dict(truth[vid])
        if vid == "ramp":  # on the route only once on b, which starts at 113 m
            on_b = {tt: 113.0 + s - 62.0 for tt, s in expected.items() if s >= 62.0}
            assert dict(zip(t.tolist(), pos.tolist(), strict=True)) == pytest.approx(on_b)
        else:
            assert dict(zip(t.tolist(), pos.tolist(), strict=True)) == pytest.approx(expected)
    ramp_times = ts.times[ts.ids == "ramp"]
    assert ramp_times.size and ramp_times.min() >= 5.0 + 62.0 / 8.0 - 1e-9
    assert np.all((ts.positions >= 0) & (ts.positions < layout.length))


def test_outflow_per_minute_is_the_hand_count() -> None:
    # 0.5 s steps over 150 s; cars leave at chosen times
    leave = {10.0: 1, 30.5: 2, 59.5: 1, 60.0: 3, 119.5: 1, 149.5: 2}
    stats = [
        StepStats(k, k * DT, 5, 1.0, 1.0, 1.0, 0.0, math.nan, 0, 0, 0, leave.get(k * DT, 0))
        for k in range(300)
    ]
    flow = outflow(stats)
    assert flow.start.tolist() == [0.0, 60.0, 120.0]
    assert flow.count.tolist() == [4, 4, 2]  # [0, 60): 1+2+1, [60, 120): 3+1, [120, 150): 2
    assert flow.covered.tolist() == [60.0, 60.0, 30.0]
    assert flow.rate.tolist() == [240.0, 240.0, 240.0]  # veh/h


def test_outflow_and_traffic_of_a_log(
    toy: tuple[McapLog, dict[str, list[tuple[float, float]]]],
) -> None:
    log, _ = toy
    stats = list(log.stats())
    # a main-road car takes 31.3 s to drive its 313 m; the ramp car 262 m / 8 m/s
    left = [t0 + 31.3 for t0 in np.arange(12) * 8.0] + [5.0 + 262 / 8.0]
    gone = [math.ceil(t / DT) * DT for t in left]  # the first logged step without the car
    hand = [sum(1 for t in gone if 60 * k <= t < 60 * (k + 1)) for k in (0, 1, 2)]
    assert outflow(stats).count.tolist() == hand
    assert summarize(log).arrived == len(left) == sum(hand)
    layout = layout_for(log)
    series = traffic_series(log, layout)
    on_route = [len(f.ids) - int("r" in f.edges or ":j_1" in f.edges) for f in log.frames()]
    assert series.count.tolist() == on_route
    assert series.density == pytest.approx(np.array(on_route) / 0.313)


def test_bad_routes_are_named(toy: tuple[McapLog, dict[str, list[tuple[float, float]]]]) -> None:
    log, _ = toy
    with pytest.raises(RecordingError, match="did you mean 'b'"):
        layout_for(log, ["a", "bb"])
    with pytest.raises(RecordingError, match=r"'b' does not lead to 'a'.*nothing"):
        layout_for(log, ["b", "a"])
    with pytest.raises(RecordingError, match=r"'a' does not lead to 'r'.*leads to b"):
        layout_for(log, ["a", "r"])


def test_a_ring_log_keeps_the_ring_position(tmp_path: Path) -> None:
    from flowrun.recording.synthetic import ring_frames

    with McapRecorder(tmp_path / "ring.mcap", metadata={"network_closed": "true"}) as rec:
        for frame, stats in ring_frames(5, 10):
            rec.write(frame, stats)
    log = open_log(tmp_path / "ring.mcap")
    assert layout_for(log) is None
    ts = time_space_points(log, route=layout_for(log))
    assert ts.positions.tolist() == [p for f in log.frames() for p in f.position.tolist()]


# --- the CLI on a real merge log ----------------------------------------------------------


@pytest.fixture
def app() -> typer.Typer:
    app = typer.Typer()

    @app.callback()
    def _root() -> None:
        pass

    register(app)
    return app


@pytest.fixture(scope="module")
def merge_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("runs")
    return run_baseline(load("merge"), steps=90, out=out).logs[0]


@pytest.mark.sumo
def test_replay_of_a_merge_log_writes_plots_and_csv(
    app: typer.Typer, merge_log: Path, tmp_path: Path
) -> None:
    csv = tmp_path / "e.csv"
    args = ["replay", str(merge_log), "--plot", "all", "--out", str(tmp_path / "p"),
            "--csv", str(csv)]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    for name in ("speeds.png", "time_space.png", "vehicle_speeds.png", "traffic.png"):
        (png,) = (tmp_path / "p").glob(f"*/{name}")  # replay's new folder of plots
        assert png.read_bytes()[:4] == b"\x89PNG"
    assert "vehicles entered" in result.stdout and "outflow" in result.stdout
    rows = sum(len(f.ids) for f in open_log(merge_log).frames())
    assert len(csv.read_text().splitlines()) == 1 + rows

    ramp = CliRunner().invoke(
        app, ["replay", str(merge_log), "--route", "inflow_merge,bottom,center", "--plot",
              "time-space", "--out", str(tmp_path / "r")],
    )  # fmt: skip
    assert ramp.exit_code == 0, ramp.output
    (png,) = (tmp_path / "r").glob("*/time_space.png")
    assert png.stat().st_size > 10_000


@pytest.mark.sumo
def test_a_wrong_route_is_one_line_and_exit_1(app: typer.Typer, merge_log: Path) -> None:
    result = CliRunner().invoke(app, ["replay", str(merge_log), "--route", "left,inflow_merge"])
    assert result.exit_code == 1
    assert "'left' does not lead to 'inflow_merge'" in result.output
    assert "Traceback" not in result.output


@pytest.mark.sumo
def test_the_merge_main_road_diagram_moves_forward_through_the_junction(
    merge_log: Path,
) -> None:
    log = open_log(merge_log)
    layout = layout_for(log)
    assert layout is not None and layout.edges == ("inflow_highway", "left", "center")
    assert any(e.startswith(":") for e in layout.offsets)
    ts = time_space_points(log, route=layout)
    edge_at = {(f.time, v): e for f in log.frames() for v, e in zip(f.ids, f.edges, strict=True)}
    on_edges = {edge_at[(t, v)] for t, v in zip(ts.times.tolist(), ts.ids.tolist(), strict=True)}
    assert on_edges <= set(layout.offsets) and ":center_1" in on_edges
    assert len(ts.times) < len(edge_at)  # the ramp's cars are left out
    crossed = 0
    for vid in set(ts.ids.tolist()):
        pos = ts.positions[ts.ids == vid]
        assert np.all(np.diff(pos) >= -1e-9)
        crossed += bool(pos.min() < layout.offsets["left"] < layout.offsets["center"] < pos.max())
    assert crossed > 3


def test_plot_stride_counts_the_cars_of_every_step(
    toy: tuple[McapLog, dict[str, list[tuple[float, float]]]], monkeypatch: pytest.MonkeyPatch
) -> None:
    from flowrun.replay import plots

    log, _ = toy
    points = sum(len(f.ids) for f in log.frames())
    first = len(next(log.frames()).ids)
    monkeypatch.setattr(plots, "MAX_POINTS", 100)
    assert plots.plot_stride(log) == math.ceil(points / 100) > math.ceil(300 * first / 100)


@pytest.mark.sumo
def test_lane_changes_are_counted_in_metrics_the_log_and_the_summary(tmp_path: Path) -> None:
    from flowrun.cli.main import app
    from flowrun.replay.summary import summarize

    config = Path(__file__).resolve().parent.parent / "configs" / "highway_lane_change.yaml"
    result = CliRunner().invoke(
        app, ["baseline", str(config), "--set", "env.horizon=300", "--out", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    run_dir = next(tmp_path.glob("highway_lane_change/*"))
    metrics = json.loads((run_dir / "metrics.json").read_text())
    counted = metrics["runs"][0]["lane_changes"]
    assert counted > 0
    log = open_log(run_dir / "run_0.mcap")
    assert sum(s.lane_changes for s in log.stats()) == counted
    assert summarize(log).lane_changes == counted
