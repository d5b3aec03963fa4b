"""Flow's clock at reset and Flow's headway without a leader (real SUMO, seconds).

Flow's ``start_simulation`` steps SUMO once on the empty network and its ``reset`` inserts the
cars and steps once more, so with ``restart_instance`` (which flowrun's reset always is) the
clock reads two steps after every reset. Flow's ``get_headway`` gives 1000 m without a leader;
its IDM then drops the interaction term (``s* = 0``), which flowrun's controllers do by reading
``inf`` in the kernel's own array.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowrun.config.params import (
    EnvParams,
    InFlows,
    NetParams,
    SumoCarFollowingParams,
    SumoParams,
    TrafficLightParams,
    VehicleParams,
)
from flowrun.config.vehicles import ControllerSpec
from flowrun.envs.test import TestEnv
from flowrun.networks.highway import HighwayNetwork
from flowrun.networks.ring import RingNetwork

pytestmark = pytest.mark.sumo


def ring_with_light(phases: list[dict[str, str]]) -> TestEnv:
    vehicles = VehicleParams()
    vehicles.add("idm", acceleration_controller=ControllerSpec("IDM"),
                 routing_controller=ControllerSpec("ContinuousRouter"), num_vehicles=5)  # fmt: skip
    tl = TrafficLightParams()
    tl.add("top", phases=phases)
    params = {"length": 230, "lanes": 1, "speed_limit": 30, "resolution": 40}
    net = RingNetwork("ring", vehicles, NetParams(additional_params=params), traffic_lights=tl)
    return TestEnv(EnvParams(horizon=10**6), SumoParams(sim_step=0.1, seed=0), net)


def test_reset_leaves_the_clock_at_two_steps_every_time() -> None:
    env = ring_with_light([{"duration": "4", "state": "G"}, {"duration": "1", "state": "y"}])
    try:
        for _ in range(2):
            env.reset(seed=0)
            assert env.k.simulation.time == pytest.approx(0.2)
            assert env.k.simulation.step_count == 0
            for _ in range(5):
                env.step(None)
            assert env.k.simulation.time == pytest.approx(0.7)
    finally:
        env.close()


def test_a_static_program_runs_from_sumos_time_zero() -> None:
    # The 4 s green began at t = 0 (Flow's empty first step included): SUMO switches it at the
    # start of the step from t = 4.0, so the state read after that step (t = 4.1) is yellow.
    env = ring_with_light([{"duration": "4", "state": "G"}, {"duration": "1", "state": "y"},
                           {"duration": "4", "state": "r"}])  # fmt: skip
    try:
        env.reset(seed=0)
        seen = []
        for _ in range(60):
            seen.append(env.k.traffic_light.get_state("top"))
            env.step(None)
        # states read at t = 0.2, 0.3, ...: green until t = 4.0, yellow from 4.1 to 5.0
        assert seen[:39] == ["G"] * 39
        assert seen[39:49] == ["y"] * 10
        assert seen[49] == "r"
    finally:
        env.close()


def highway(vph: float, sim_step: float, n_lanes: int = 1) -> TestEnv:
    vehicles = VehicleParams()
    vehicles.add(
        "human",
        acceleration_controller=ControllerSpec("IDM", {"v0": 30, "a": 1, "noise": 0}),
        num_vehicles=0,
        car_following_params=SumoCarFollowingParams(speed_mode="obey_safe_speed"),
    )
    inflows = InFlows()
    inflows.add("highway_0", "human", vehs_per_hour=vph, depart_speed=10)
    params = {"length": 500, "lanes": n_lanes, "speed_limit": 30, "num_edges": 1}
    net = HighwayNetwork("hw", vehicles, NetParams(additional_params=params, inflows=inflows))
    return TestEnv(EnvParams(horizon=10**6), SumoParams(sim_step=sim_step, seed=0), net)


def test_cars_an_inflow_inserts_in_the_reset_step_are_on_the_road_after_reset() -> None:
    # 1 s steps: the inflow's first car (begin 1 s) enters in reset's own step, as in Flow
    env = highway(vph=1800, sim_step=1.0)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        assert env.k.simulation.time == pytest.approx(2.0)
        assert vk.get_ids() == list(vk.api.vehicle.getIDList()) == ["flow_0.0"]
        assert vk.get_speed("flow_0.0") == pytest.approx(10.0)
        assert vk.get_departed_ids() == []  # Flow's reset counts no departure
        env.step(None)
        assert vk.num_vehicles == len(vk.api.vehicle.getIDList())
    finally:
        env.close()


def test_headway_without_leader_is_flows_1000_and_idm_drives_free() -> None:
    env = highway(vph=1800, sim_step=0.1)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        while vk.num_vehicles < 2:
            env.step(None)
        first, second = "flow_0.0", "flow_0.1"
        assert vk.get_leader(first) is None and vk.get_leader(second) == first
        assert vk.get_headway(first) == 1000.0
        assert vk.get_headway([first, "nope"]) == [1000.0, -1001.0]
        assert vk.headway[vk.table.row(first)] == math.inf  # what controllers test
        assert 0 < vk.get_headway(second) < 1000.0
        v = vk.get_speed(first)
        env.step(None)
        # free-road IDM, a (1 - (v/v0)^4): 1000 m is not read as a gap (Flow's s* = 0)
        assert vk.get_accel(first) == pytest.approx(1.0 * (1 - (v / 30) ** 4), abs=1e-12)
        assert vk.get_speed(first) == pytest.approx(v + 0.1 * vk.get_accel(first), abs=1e-9)
        gaps = np.array(vk.get_headway(vk.get_ids()))
        assert (gaps == 1000.0).sum() == 1
    finally:
        env.close()
