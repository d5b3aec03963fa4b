"""MCAP logs of an open network: the merge with inflows, cars entering and leaving.

Real SUMO, seeded: Flow's merge (``configs/merge.yaml``) with one simulation step per env step,
run by ``Experiment`` as ``flowrun baseline`` does, into a full log and a thinned one at once.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from flowrun.envs.base import Env
from flowrun.envs.factory import make_env
from flowrun.experiment import Experiment
from flowrun.experiment.baseline import open_run_log, run_baseline
from flowrun.recording import McapLog, StepStats, VehicleFrame, open_log
from flowrun.recording.schema import StepStatsMsg, decode_stats, encode_stats
from tests.conftest import load

STEPS = 240  # 120 s at 0.5 s: the first cars reach the end of the road and leave
CHECK_AT = (1, 60, 150, 239)  # steps at which SUMO's own positions are read
THIN = 4


class Tee:
    """A frame sink writing to two recorders (every step, and every ``THIN``-th)."""

    def __init__(self, *sinks: Any) -> None:
        self.sinks = sinks

    def write(self, frame: VehicleFrame, stats: StepStats) -> None:
        for sink in self.sinks:
            sink.write(frame, stats)

    def close(self) -> None:
        for sink in self.sinks:
            sink.close()


@pytest.fixture(scope="module")
def merge_run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    tmp = tmp_path_factory.mktemp("merge")
    cfg = load("merge", "env.sims_per_step=1", f"env.horizon={STEPS}")
    env = make_env(cfg, work_dir=tmp / "sumo")
    departed: list[int] = []
    arrived: list[int] = []
    sumo_xy: dict[float, dict[str, tuple[float, float]]] = {}
    initial: list[str] = []

    def count(e: Env) -> int:
        vk = e.k.vehicle
        departed.append(len(vk.get_departed_ids()))
        arrived.append(len(vk.get_arrived_ids()))
        if len(departed) in CHECK_AT:
            api = vk.api
            sumo_xy[e.k.simulation.time] = {v: api.vehicle.getPosition(v) for v in vk.get_ids()}
        return 0

    def sink(run: int) -> Tee:
        initial.extend(env.k.vehicle.get_ids())
        full = open_run_log(tmp / "full.mcap", env, cfg, 0, run)
        thin = open_run_log(tmp / "thin.mcap", env, cfg, 0, run, record_every=THIN)
        return Tee(full, thin)

    try:
        exp = Experiment(env, sink_factory=sink, custom_callables={"count": count})
        exp.run(1, STEPS, seed=0)
    finally:
        env.close()
    return {
        "full": open_log(tmp / "full.mcap"),
        "thin": open_log(tmp / "thin.mcap"),
        "departed": departed,
        "arrived": arrived,
        "sumo_xy": sumo_xy,
        "initial": initial,
        "metrics": exp.metrics[0],
    }


pytestmark = pytest.mark.sumo


def test_frames_hold_a_changing_set_of_cars_with_every_column_complete(
    merge_run: dict[str, Any],
) -> None:
    frames = list(merge_run["full"].frames())
    assert len(frames) == STEPS + 1  # the state after reset, then every step
    first, last = set(frames[0].ids), set(frames[-1].ids)
    assert first == set(merge_run["initial"])
    assert last - first and first - last  # new cars came, some of the first ones left
    assert len({tuple(f.ids) for f in frames}) > 20
    for f in frames:
        n = len(f.ids)
        assert len(set(f.ids)) == n
        columns = (f.types, f.edges, f.lanes, f.lane_pos, f.position, f.odometer, f.x, f.y,
                   f.speed, f.accel_cmd, f.accel_real, f.headway, f.leader, f.is_rl)  # fmt: skip
        assert all(len(c) == n for c in columns)
        assert set(f.leader) <= set(f.ids) | {""}


def test_departures_and_arrivals_in_the_stats_match_the_kernel(merge_run: dict[str, Any]) -> None:
    stats = list(merge_run["full"].stats())
    dep = [s.departed for s in stats]
    arr = [s.arrived for s in stats]
    assert dep[0] == arr[0] == 0  # the reset: the placed cars are not departures
    assert dep[1:] == merge_run["departed"] and arr[1:] == merge_run["arrived"]
    assert sum(dep) > 20 and sum(arr) > 5
    # conservation at every step: placed + entered - left = cars in the network
    alive = len(merge_run["initial"])
    for s in stats:
        alive += s.departed - s.arrived
        assert s.num_vehicles == alive
    seen = {v for f in merge_run["full"].frames() for v in f.ids}
    assert len(seen) == len(merge_run["initial"]) + sum(dep)
    m = merge_run["metrics"]
    assert (m.departed, m.arrived) == (sum(dep), sum(arr))


def test_a_thinned_log_keeps_the_total_departures_and_arrivals(merge_run: dict[str, Any]) -> None:
    full = list(merge_run["full"].stats())
    thin = list(merge_run["thin"].stats())
    assert [s.step for s in thin] == [s.step for s in full if s.step % THIN == 0]
    logged_until = thin[-1].step
    kept = [s for s in full if s.step <= logged_until]
    assert sum(s.departed for s in thin) == sum(s.departed for s in kept)
    assert sum(s.arrived for s in thin) == sum(s.arrived for s in kept)


def test_x_y_are_sumos_positions(merge_run: dict[str, Any]) -> None:
    log: McapLog = merge_run["full"]
    checked = 0
    for t, positions in merge_run["sumo_xy"].items():
        (frame,) = log.frames(t, t)
        assert set(frame.ids) == set(positions)
        for i, vid in enumerate(frame.ids):
            assert (frame.x[i], frame.y[i]) == pytest.approx(positions[vid], abs=1e-9)
            checked += 1
    assert len(merge_run["sumo_xy"]) == len(CHECK_AT) and checked > 40


def test_positions_are_flows_absolute_positions(merge_run: dict[str, Any]) -> None:
    log: McapLog = merge_run["full"]
    starts = json.loads(log.metadata["edge_starts"])
    assert any(e.startswith(":") for e in starts)  # junction-internal edges included
    for frame in log.frames(50.0, 60.0):
        for i, edge in enumerate(frame.edges):
            assert frame.position[i] == pytest.approx(starts[edge] + frame.lane_pos[i])


def test_metadata_names_the_main_road(merge_run: dict[str, Any]) -> None:
    meta = merge_run["full"].metadata
    assert json.loads(meta["main_route"]) == ["inflow_highway", "left", "center"]
    assert meta["network_closed"] == "false"
    assert float(meta["network_length"]) > 700.0
    assert "network.net.xml" in merge_run["full"].attachments


def test_baseline_writes_entries_and_exits_to_metrics_and_log(tmp_path: Path) -> None:
    result = run_baseline(load("merge"), steps=40, out=tmp_path)
    metrics = json.loads((result.run_dir / "metrics.json").read_text())["runs"][0]
    stats = list(open_log(result.logs[0]).stats())
    assert metrics["departed"] == sum(s.departed for s in stats) > 0
    assert metrics["arrived"] == sum(s.arrived for s in stats)


def test_stats_of_old_logs_read_zero_entries_and_exits() -> None:
    old = StepStatsMsg(step=7, time=0.7, num_vehicles=3, mean_speed=1.0, collisions=1)
    stats = decode_stats(old.SerializeToString())
    assert (stats.departed, stats.arrived, stats.collisions) == (0, 0, 1)


@pytest.mark.parametrize("dep_arr", [(0, 0), (1, 0), (0, 300), (2**20, 5)])
def test_stats_with_entries_and_exits_equal_the_protobuf_library(
    dep_arr: tuple[int, int],
) -> None:
    dep, arr = dep_arr
    stats = StepStats(9, 0.9, 4, 2.0, 1.0, 3.0, 0.5, math.nan, 0, 0, dep, arr)
    msg = StepStatsMsg(
        step=9, time=0.9, num_vehicles=4, mean_speed=2.0, min_speed=1.0, max_speed=3.0,
        speed_std=0.5, reward=math.nan, departed=dep, arrived=arr,
    )  # fmt: skip
    assert encode_stats(stats) == msg.SerializeToString()
    back = decode_stats(encode_stats(stats))
    assert (back.departed, back.arrived) == dep_arr
