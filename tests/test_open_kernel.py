"""The kernel on an open network: cars come and go, leaders across a merge junction.

A small merge (highway 200 m + ramp joining at node ``b``, then 100 m + 100 m to the exit),
built as data here so these tests do not depend on any network class. Real SUMO, seeded.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import gymnasium
import numpy as np
import pytest

from flowrun.config.params import (
    ControllerSpec,
    EnvParams,
    InFlows,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    VehicleParams,
)
from flowrun.envs.base import Env
from flowrun.kernel.open_reader import OpenReader
from flowrun.kernel.open_road import Following
from flowrun.networks.base import Edge, Network, NetworkSpec, Node, StartPositions
from flowrun.networks.registry import network_class
from tests.sumo_truth import compare_leaders_with_sumo

pytestmark = pytest.mark.sumo


class ToyMerge(Network):
    """Highway ``hw`` (a→b) and ramp ``ramp`` (m→b) merge into ``ce`` (b→c), then ``out``."""

    network_type: ClassVar[str] = "toy_merge"

    def build_spec(self) -> NetworkSpec:
        nodes = (
            Node("a", 0.0, 0.0),
            Node("b", 200.0, 0.0),
            Node("c", 300.0, 0.0),
            Node("d", 400.0, 0.0),
            Node("m", 200.0 - 100 / math.sqrt(2), -100 / math.sqrt(2)),
        )
        edges = (
            Edge("hw", "a", "b", 200.0, 1, 30.0, priority=2),
            Edge("ramp", "m", "b", 100.0, 1, 30.0, priority=1),
            Edge("ce", "b", "c", 100.0, 1, 30.0, priority=2),
            Edge("out", "c", "d", 100.0, 1, 30.0, priority=2),
        )
        routes = {
            "hw": ("hw", "ce", "out"),
            "ramp": ("ramp", "ce", "out"),
            "ce": ("ce", "out"),
            "out": ("out",),
        }
        starts = {"hw": 0.0, "ce": 210.0, "out": 320.0, "ramp": 500.0}
        return NetworkSpec(
            nodes, edges, routes, starts, 500.0, internal_links=True, main_route=("hw", "ce", "out")
        )

    def start_positions(self, rng: np.random.Generator) -> StartPositions:
        n = self.vehicles.num_vehicles
        return StartPositions(["hw"] * n, [150.0 - 20.0 * i for i in range(n)], [0] * n)


class Drive(Env):
    """No RL: the human controllers drive."""

    @property
    def action_space(self) -> gymnasium.spaces.Box:
        return gymnasium.spaces.Box(-1.0, 1.0, (1,), np.float32)

    @property
    def observation_space(self) -> gymnasium.spaces.Box:
        return gymnasium.spaces.Box(-np.inf, np.inf, (1,), np.float32)

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        pass

    def get_state(self) -> Any:
        return np.zeros(1)


def make(
    hw_vph: float = 1800.0, ramp_vph: float = 300.0, dt: float = 0.1, initial: int = 3
) -> Drive:
    vehicles = VehicleParams()
    vehicles.add(
        "human",
        acceleration_controller=ControllerSpec("IDM", {"noise": 0.0}),
        num_vehicles=initial,
        car_following_params=SumoCarFollowingParams(speed_mode="obey_safe_speed"),
    )
    inflows = InFlows()
    inflows.add("hw", "human", vehs_per_hour=hw_vph, depart_speed=10, depart_lane="free")
    if ramp_vph:
        inflows.add("ramp", "human", vehs_per_hour=ramp_vph, depart_speed=10)
    net = ToyMerge("toy", vehicles, NetParams(inflows=inflows), InitialConfig())
    return Drive(EnvParams(horizon=10**9), SumoParams(sim_step=dt, seed=3), net)


def on_network(name: str) -> Drive:
    """Flow's networks with human traffic: inflows on the open ones, 14 cars on the eight."""
    vehicles = VehicleParams()
    router = ControllerSpec("ContinuousRouter") if name == "figure_eight" else None
    # at the grid's lights SUMO drives (IDM does not see red lights), as in Flow's grid
    driver = "SimCarFollowingController" if name == "traffic_light_grid" else "IDM"
    vehicles.add(
        "human",
        acceleration_controller=ControllerSpec(driver, {"noise": 0.2} if driver == "IDM" else {}),
        routing_controller=router,
        num_vehicles=14 if name == "figure_eight" else 0,
        car_following_params=SumoCarFollowingParams(
            speed_mode="all_checks" if name == "traffic_light_grid" else "obey_safe_speed"
        ),
        lane_change_params=SumoLaneChangeParams(lane_change_mode="sumo_default"),
    )
    inflows = InFlows()
    params: dict[str, Any] = {}
    if name == "merge":
        inflows.add("inflow_highway", "human", vehs_per_hour=2000, depart_speed=10)
        inflows.add("inflow_merge", "human", vehs_per_hour=300, depart_speed=7.5)
    elif name == "highway":
        inflows.add("highway_0", "human", vehs_per_hour=4000, depart_speed=20,
                    depart_lane="free")  # fmt: skip
        params = {"length": 600, "lanes": 3, "num_edges": 2, "use_ghost_edge": True}
    elif name == "traffic_light_grid":
        params = {"grid_array": {"row_num": 2, "col_num": 2, "inner_length": 150,
                                 "short_length": 150, "long_length": 150, "cars_top": 0,
                                 "cars_bot": 0, "cars_left": 0, "cars_right": 0}}  # fmt: skip
        for edge in ("bot0_0", "bot1_0", "right0_0", "right1_0", "top0_2", "top1_2",
                     "left2_0", "left2_1"):  # fmt: skip
            inflows.add(edge, "human", vehs_per_hour=500, depart_speed=10)
    cls = network_class(name)
    net = cls(name, vehicles, NetParams(additional_params=params, inflows=inflows or None))
    return Drive(EnvParams(horizon=10**9), SumoParams(sim_step=0.2, seed=3), net)


NETWORKS = ["toy_merge", "merge", "figure_eight", "highway", "traffic_light_grid"]


def make_on(name: str) -> Drive:
    return make() if name == "toy_merge" else on_network(name)


@pytest.mark.parametrize("name", NETWORKS)
def test_leaders_and_headways_equal_sumos_getleader_for_every_car(name: str) -> None:
    env = make_on(name)
    try:
        env.reset(seed=1)
        compared, across_junction = compare_leaders_with_sumo(env, 400)
        assert compared > 2000
        assert across_junction > 50  # leaders past the lane's end really were exercised
    finally:
        env.close()


@pytest.mark.parametrize("name", NETWORKS)
def test_followers_are_the_nearest_car_whose_leader_sumo_says_it_is(name: str) -> None:
    # Flow's rule (its kernel sets the follower of each car's leader), with SUMO's getLeader
    # as the truth; of several cars with the same leader (lanes merging), the nearest.
    env = make_on(name)
    try:
        env.reset(seed=1)
        vk = env.k.vehicle
        v = vk.api.vehicle
        for _ in range(300):
            env.step(None)
        checked = merging = 0
        for _ in range(50):
            env.step(None)
            ids = vk.get_ids()
            behind: dict[str, list[tuple[float, str]]] = {}
            for vid in ids:
                found = v.getLeader(vid, 500.0)
                if found and found[0]:
                    gap = found[1] + v.getMinGap(vid)
                    behind.setdefault(found[0], []).append((gap, vid))
            for vid in ids:
                cands = sorted(behind.get(vid, []))
                if not cands:
                    assert vk.get_follower(vid) is None, vid
                    assert vk.get_tailway(vid) == math.inf
                    continue
                gap, nearest = cands[0]
                assert vk.get_follower(vid) == nearest, vid
                assert vk.get_tailway(vid) == pytest.approx(gap, abs=1e-6), vid
                checked += 1
                merging += len(cands) > 1
        assert checked > 300
        if name in ("toy_merge", "merge"):
            assert merging > 0  # two cars with one leader really were exercised
    finally:
        env.close()


def test_every_departed_car_is_in_the_network_or_arrived_at_every_step() -> None:
    env = make()
    try:
        env.reset(seed=2)
        vk = env.k.vehicle
        departed = set(vk.get_ids())
        arrived: set[str] = set()
        for _ in range(900):
            env.step(None)
            departed |= set(vk.get_departed_ids())
            arrived |= set(vk.get_arrived_ids())
            live = set(vk.get_ids())
            assert live == departed - arrived
            assert set(vk.api.vehicle.getIDList()) == live
            assert len(vk.speed) == len(live) == len(vk.headway) == len(vk.position)
        assert len(arrived) > 10
    finally:
        env.close()


def test_inflow_of_1800_veh_per_hour_delivers_it_over_ten_minutes() -> None:
    env = make(hw_vph=1800.0, ramp_vph=0.0, dt=0.5, initial=0)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        count = 0
        for _ in range(1200):  # 600 s
            env.step(None)
            count += len(vk.get_departed_ids())
        assert count * 6 == pytest.approx(1800.0, rel=0.05)
        assert vk.get_inflow_rate(600.0) == pytest.approx(1800.0, rel=0.05)
    finally:
        env.close()


def test_a_new_car_is_driven_by_its_types_controller_from_its_first_step() -> None:
    env = make(initial=0)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        seen = 0
        for _ in range(300):
            env.step(None)
            for vid in vk.get_departed_ids():
                assert vk.get_type(vid) == "human"
            # a step later every car not on a junction lane got an IDM command
            cmd = vk.last_cmd
            if cmd.size:
                inside = vk.on_internal
                seen += int(np.isfinite(cmd[~inside]).sum())
        assert seen > 1000
    finally:
        env.close()


def test_positions_along_the_network_use_edge_starts_including_junction_edges() -> None:
    env = make()
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        starts = env.k.network.total_edgestarts_dict
        internal = [e for e in starts if e.startswith(":")]
        assert internal  # the junction's lanes got starts too
        on_junction = 0
        for _ in range(300):
            env.step(None)
            for vid in vk.get_ids():
                edge = vk.get_edge(vid)
                x = env.k.network.get_x(edge, vk.get_position(vid))
                assert vk.get_x_by_id(vid) == pytest.approx(x)
                on_junction += edge.startswith(":")
        assert on_junction > 0
        # the highway's junction lane starts where the highway's lane ends
        hw_lane = vk.api.lane.getLength("hw_0")
        via = [link[4] for link in vk.api.lane.getLinks("hw_0") if link[4]]
        assert starts[via[0].rpartition("_")[0]] == pytest.approx(hw_lane)
    finally:
        env.close()


def test_same_seed_gives_the_same_departures_and_trajectories() -> None:
    def roll() -> list[tuple[str, ...]]:
        env = make()
        try:
            env.reset(seed=5)
            out = []
            for _ in range(200):
                env.step(None)
                vk = env.k.vehicle
                out.append(tuple(vk.get_ids()) + tuple(f"{s:.12f}" for s in vk.speed))
            return out
        finally:
            env.close()

    assert roll() == roll()


def test_network_length_counts_the_junctions_and_non_internal_length_does_not() -> None:
    env = make()
    try:
        env.reset(seed=0)
        net = env.k.network
        assert net.non_internal_length() == pytest.approx(500.0)
        lane = env.k.vehicle.api.lane
        junctions = sum(
            lane.getLength(f"{e}_0") for e in {":b_0", ":b_1", ":c_0"} if f"{e}_0" in
            lane.getIDList()
        )  # fmt: skip
        assert junctions > 0
        assert net.length() == pytest.approx(500.0 + junctions)
    finally:
        env.close()


@pytest.mark.parametrize("name", ["figure_eight", "toy_merge"])
def test_leaders_replayed_from_the_last_step_equal_a_fresh_search_bit_for_bit(name: str) -> None:
    # Following reuses the last step's order while every car stays on its lane; a Following
    # with no past must find the same leaders, followers and the same floats
    env = make_on(name)
    try:
        env.reset(seed=1)
        reader = env.k.vehicle.reader
        assert isinstance(reader, OpenReader)
        following = reader._following
        graph, edge_pos = following.graph, following._edge_pos
        compute = following.compute
        replayed = steps = 0

        def checked(pop: Any, lane_key: Any, lane_pos: Any, routes: Any = None,
                    lists: Any = None) -> Any:  # fmt: skip
            nonlocal replayed, steps
            plan = following._plan
            fresh = Following(following._get_leader, graph, edge_pos)
            want = fresh.compute(pop, lane_key, lane_pos, routes)
            got = compute(pop, lane_key, lane_pos, routes, lists)
            for a, b in zip(got, want, strict=True):
                assert a.dtype == b.dtype and a.tobytes() == b.tobytes()
            assert following.complete == fresh.complete
            replayed += plan is not None and following._plan is plan
            steps += 1
            return got

        following.compute = checked  # type: ignore[method-assign]
        for _ in range(600):
            env.step(None)
        assert steps >= 600
        assert replayed > steps // 2  # the replay really was exercised
    finally:
        env.close()
