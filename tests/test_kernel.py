"""The kernel: who follows whom on a ring (pure), and the SUMO-backed getters and commands."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from flowrun.envs.factory import make_env
from flowrun.errors import ConfigError
from flowrun.experiment.runner import Experiment
from flowrun.kernel.following import RingFollowing, leaders_on_ring
from flowrun.recording.reader import open_log
from flowrun.recording.writer import McapRecorder

INF = math.inf


def ring(
    position: list[float], lanes: list[int] | None = None, length: float = 100.0, car: float = 5.0
) -> tuple[list[int], list[int], list[float]]:
    n = len(position)
    leader, follower, headway = leaders_on_ring(
        np.array(position, dtype=float),
        np.array(lanes if lanes is not None else [0] * n, dtype=np.int64),
        np.full(n, car),
        length,
    )
    return leader.tolist(), follower.tolist(), headway.tolist()


# --- leaders_on_ring (pure) ----------------------------------------------------------------


def test_leaders_follow_position_order_not_index_order() -> None:
    # positions 50, 10, 30 on a 100 m ring: 1 -> 2 -> 0 -> 1 (wrapping)
    leader, follower, headway = ring([50.0, 10.0, 30.0])
    assert leader == [1, 2, 0]
    assert follower == [2, 0, 1]
    # gaps: 0->1 wraps: (10 - 50) mod 100 - 5 = 55; 1->2: 20 - 5; 2->0: 20 - 5
    assert headway == pytest.approx([55.0, 15.0, 15.0])


def test_leader_of_the_front_car_wraps_around_the_ring() -> None:
    leader, _, headway = ring([98.0, 3.0], length=100.0, car=4.0)
    assert leader == [1, 0]
    # 98 -> 3 across the ring end: 5 m between front bumpers, minus the leader's 4 m
    assert headway == pytest.approx([1.0, 91.0])


def test_single_car_has_no_leader_and_infinite_headway() -> None:
    leader, follower, headway = ring([42.0])
    assert leader == [-1]
    assert follower == [-1]
    assert headway == [INF]


def test_no_cars_gives_empty_arrays() -> None:
    assert ring([]) == ([], [], [])


def test_lanes_are_independent_rings() -> None:
    # lane 0: cars 0 (10 m), 2 (60 m); lane 1: cars 1 (20 m), 3 (40 m); car 4 alone in lane 2
    leader, follower, headway = ring([10.0, 20.0, 60.0, 40.0, 0.0], lanes=[0, 1, 0, 1, 2])
    assert leader == [2, 3, 0, 1, -1]
    assert follower == [2, 3, 0, 1, -1]
    assert headway == pytest.approx([45.0, 15.0, 45.0, 75.0, INF])


def test_lengths_of_the_leader_not_the_ego_are_subtracted() -> None:
    leader, _, headway = leaders_on_ring(
        np.array([0.0, 20.0]), np.zeros(2, dtype=np.int64), np.array([3.0, 7.0]), 100.0
    )
    assert leader.tolist() == [1, 0]
    assert headway.tolist() == pytest.approx([20.0 - 7.0, 80.0 - 3.0])


def test_ring_following_reuses_the_order_and_matches_a_fresh_sort() -> None:
    # 7 cars of two lengths drive 2,000 steps at different speeds without passing: headways
    # from the unwrapped positions equal a fresh sort of the wrapped ones at every step.
    rng = np.random.default_rng(3)
    length, n = 230.0, 7
    lengths = np.array([5.0, 5.0, 4.0, 5.0, 7.0, 5.0, 5.0])
    start = np.sort(rng.uniform(0, length, n))[::-1].copy()  # index order != ring order
    following = RingFollowing(lengths, length)
    odometer = np.zeros(n)
    for step in range(2000):
        u = start + odometer
        leader, follower, headway = following.compute(u)
        ref_leader, ref_follower, ref_headway = leaders_on_ring(
            np.mod(u, length), np.zeros(n, dtype=np.int64), lengths, length
        )
        assert leader.tolist() == ref_leader.tolist(), step
        assert follower.tolist() == ref_follower.tolist(), step
        assert headway == pytest.approx(ref_headway, abs=1e-9), step
        # everyone moves, but never more than the gap ahead: no passing
        odometer = odometer + np.minimum(rng.uniform(0, 3, n), np.maximum(headway, 0) * 0.9)
    assert following.complete
    assert odometer.min() > 230.0  # every car lapped the ring at least once


def test_ring_following_finds_the_new_order_after_a_car_passes_its_leader() -> None:
    lengths = np.full(3, 5.0)
    following = RingFollowing(lengths, 100.0)
    following.compute(np.array([10.0, 30.0, 60.0]))  # 0 -> 1 -> 2 -> 0
    leader, _, headway = following.compute(np.array([40.0, 30.0, 60.0]))  # car 0 jumped car 1
    assert leader.tolist() == [2, 0, 1]
    assert headway.tolist() == pytest.approx([15.0, 5.0, 65.0])


def test_ring_following_of_one_car_has_no_leader() -> None:
    following = RingFollowing(np.array([5.0]), 100.0)
    leader, follower, headway = following.compute(np.array([250.0]))
    assert (leader.tolist(), follower.tolist(), headway.tolist()) == ([-1], [-1], [INF])
    assert not following.complete


# --- getters against raw libsumo -----------------------------------------------------------


def ring_gap(a: float, b: float, length: float) -> float:
    """Smallest distance between two ring positions (m)."""
    return abs((a - b + length / 2) % length - length / 2)


@pytest.mark.sumo
def test_getters_agree_with_raw_libsumo(config: Any) -> None:
    env = make_env(config("sugiyama"))
    try:
        env.read_xy = True  # as when recording: x, y read every step
        env.reset(seed=0)
        api = env.k.process.api  # the libsumo module of this simulation
        starts = env.k.network.total_edgestarts_dict
        vk = env.k.vehicle
        checked = 0
        for step in range(1, 901):
            before = dict(zip(vk.get_ids(), vk.get_speed(vk.get_ids()), strict=True))
            env.step(None)
            if step % 150:
                continue
            for vid in vk.get_ids():
                assert vk.get_2d_position(vid) == tuple(api.vehicle.getPosition(vid))
                realised = (api.vehicle.getSpeed(vid) - before[vid]) / 0.1
                assert vk.get_realized_accel(vid) == pytest.approx(realised, abs=1e-12)
                edge = api.vehicle.getRoadID(vid)
                x = starts[edge] + api.vehicle.getLanePosition(vid)
                assert ring_gap(vk.get_x_by_id(vid), x, env.k.network.length()) < 1e-9
                assert vk.get_edge(vid) == edge
                assert vk.get_position(vid) == pytest.approx(
                    api.vehicle.getLanePosition(vid), abs=1e-9
                )
                assert vk.get_speed(vid) == api.vehicle.getSpeed(vid)
                assert vk.get_lane(vid) == api.vehicle.getLaneIndex(vid)
                found = api.vehicle.getLeader(vid, 1000.0)
                assert found is not None and found[0], vid  # everyone has a leader on a ring
                lead_id, gap = found
                assert vk.get_leader(vid) == lead_id
                assert vk.get_follower(lead_id) == vid
                assert vk.get_headway(vid) == pytest.approx(
                    gap + api.vehicle.getMinGap(vid), abs=1e-9
                )
                checked += 1
        assert checked == 6 * 22
        assert min(vk.get_headway(vk.get_ids())) < 5.0  # checked while cars were close
    finally:
        env.close()


@pytest.mark.sumo
@pytest.mark.parametrize("lanes", [1, 2])
def test_positions_placed_on_the_lane_shapes_equal_sumos(config: Any, lanes: int) -> None:
    # What a recorded frame's x/y are computed with (a batch of steps at once) against
    # libsumo's getPosition, car by car, while the cars drive around the ring (and, on two
    # lanes, change lanes).
    env = make_env(config("sugiyama", f"network.lanes={lanes}", "network.length=260"))
    try:
        env.reset(seed=0)
        api = env.k.process.api
        vk = env.k.vehicle
        placement = vk.placement()
        worst = 0.0
        for step in range(1, 1201):
            env.step(None)
            if step % 100:
                continue
            x, y = placement.xy(vk.position[None, :], vk.lanes[None, :])
            edge, lane_pos = placement.edges.locate(vk.position)
            names = placement.edges.edge_names(edge)
            for i, vid in enumerate(vk.get_ids()):
                sx, sy = api.vehicle.getPosition(vid)
                worst = max(worst, abs(x[0, i] - sx), abs(y[0, i] - sy))
                assert names[i] == api.vehicle.getRoadID(vid)
                assert lane_pos[i] == pytest.approx(api.vehicle.getLanePosition(vid), abs=1e-9)
        assert worst < 1e-9
    finally:
        env.close()


@pytest.mark.sumo
def test_continuous_router_keeps_cars_circling_for_5000_steps(config: Any) -> None:
    # 4 cars on a short ring lap it dozens of times; a length that is not a multiple of
    # 0.04 m also checks that SUMO's lanes add up to the ring exactly (no drift per lap).
    length = 230.3
    env = make_env(
        config("sugiyama", "vehicles[0].count=4", f"network.length={length}", "env.horizon=5000")
    )
    try:
        env.reset(seed=0)
        api = env.k.process.api
        for _ in range(5000):
            env.step(None)
            assert api.vehicle.getIDCount() == 4
        vk = env.k.vehicle
        assert min(vk.get_distance(v) for v in vk.get_ids()) > 40 * length
        starts = env.k.network.total_edgestarts_dict
        for vid in vk.get_ids():
            x = starts[api.vehicle.getRoadID(vid)] + api.vehicle.getLanePosition(vid)
            assert ring_gap(vk.get_x_by_id(vid), x, length) < 1e-6
        assert env.k.simulation.collisions == 0
    finally:
        env.close()


@pytest.mark.sumo
def test_collision_is_counted_and_terminates_the_episode(config: Any) -> None:
    env = make_env(config("sugiyama"))
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        victim = vk.get_ids()[0]
        # after the IDM controller, every step: ram the car ahead (speed mode aggressive)
        env.additional_command = lambda: vk.apply_acceleration(victim, 20.0)  # type: ignore[method-assign]
        terminated = False
        for _ in range(100):
            _, _, terminated, _, info = env.step(None)
            if terminated:
                break
        assert terminated
        assert info["collisions"] > 0
        assert victim in env.k.simulation.colliding_ids
    finally:
        env.close()


# --- configuration errors and rendering ----------------------------------------------------


def test_too_many_cars_for_the_ring_is_a_config_error(config: Any) -> None:
    with pytest.raises(ConfigError, match="ring") as err:
        config("sugiyama", "vehicles[0].count=40")
    assert "network.length" in str(err.value)


@pytest.mark.sumo
def test_frames_completed_in_batches_equal_frames_read_step_by_step(
    config: Any, tmp_path: Path
) -> None:
    # Recording derives edges, lane positions, x/y and realised accelerations for 256 steps
    # at a time; reading x/y from SUMO every step (env.read_xy) takes the per-step path.
    def frames(per_step: bool) -> list[Any]:
        env = make_env(config("sugiyama", "env.horizon=600"))
        env.read_xy = per_step
        path = tmp_path / f"{per_step}.mcap"
        try:
            sink = lambda run: McapRecorder(path, metadata={}, attachments={})  # noqa: E731
            Experiment(env, sink_factory=sink).run(1, 600, seed=0)
        finally:
            env.close()
        return list(open_log(path).frames())

    batched, per_step = frames(False), frames(True)
    assert len(batched) == len(per_step) == 601
    for a, b in zip(batched, per_step, strict=True):
        assert a.edges == b.edges
        for column in ("lane_pos", "speed", "accel_real", "headway", "position"):
            assert getattr(a, column).tolist() == getattr(b, column).tolist(), column
        assert np.abs(a.x - b.x).max() < 1e-9 and np.abs(a.y - b.y).max() < 1e-9
    assert {e for f in batched for e in f.edges} == {"bottom", "right", "top", "left"}


@pytest.mark.sumo
def test_ring_cars_without_continuous_router_leave_at_their_routes_end_as_in_flow(
    tmp_path: Path,
) -> None:
    # Flow: a car whose route ends leaves the network; the ring shortcuts assume nobody
    # leaves, so such a ring runs on the general path (and is logged like any network).
    from flowrun.config.params import (
        EnvParams,
        InitialConfig,
        NetParams,
        SumoCarFollowingParams,
        SumoParams,
        VehicleParams,
    )
    from flowrun.controllers import SimCarFollowingController
    from flowrun.envs import TestEnv
    from flowrun.networks.ring import RingNetwork

    vehicles = VehicleParams()
    vehicles.add("u", acceleration_controller=(SimCarFollowingController, {}),
                 routing_controller=None, num_vehicles=4,
                 car_following_params=SumoCarFollowingParams(max_speed=12))  # fmt: skip
    params = {"length": 230, "lanes": 1, "speed_limit": 30, "resolution": 40}
    net = RingNetwork("r", vehicles, NetParams(additional_params=params), InitialConfig())
    env = TestEnv(EnvParams(horizon=400), SumoParams(sim_step=0.1), net)

    def sink(run: int) -> McapRecorder:
        return McapRecorder(tmp_path / f"run_{run}.mcap", metadata={}, attachments={})

    try:
        Experiment(env, sink_factory=sink).run(1, 400)
        assert env.k.vehicle.num_vehicles == 0
    finally:
        env.close()
    counts = [len(f.ids) for f in open_log(tmp_path / "run_0.mcap").frames()]
    assert counts[0] == 4 and counts[-1] == 0
    assert counts == sorted(counts, reverse=True)  # they leave one by one, nobody returns
