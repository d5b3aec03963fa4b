"""``TrafficLightParams.add(node)`` on any network makes that node a traffic-light junction, as
Flow's network generation does (real SUMO: a ring with a light at ``top``), and the grid takes
the ring parameters Flow's own grid set-ups pass without using them."""

from __future__ import annotations

import pytest

from flowrun.config.params import (
    EnvParams,
    NetParams,
    SumoParams,
    TrafficLightParams,
    VehicleParams,
)
from flowrun.controllers import ContinuousRouter, IDMController
from flowrun.envs import TestEnv
from flowrun.errors import ConfigError
from flowrun.networks import RingNetwork
from flowrun.networks.traffic_light_grid import TrafficLightGridNetwork


def ring_with_light(lanes: int, lights: TrafficLightParams) -> TestEnv:
    vehicles = VehicleParams()
    vehicles.add("idm", acceleration_controller=(IDMController, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=1)  # fmt: skip
    net = NetParams(additional_params={"length": 230, "lanes": lanes, "speed_limit": 30,
                                       "resolution": 40})  # fmt: skip
    network = RingNetwork("tl", vehicles, net, traffic_lights=lights)
    return TestEnv(EnvParams(), SumoParams(sim_step=0.1), network)


def test_a_light_added_on_a_ring_node_controls_its_lanes() -> None:
    lights = TrafficLightParams()
    lights.add("top")
    env = ring_with_light(2, lights)
    assert {n.id: n.type for n in env.network.spec.nodes}["top"] == "traffic_light"
    assert {n.id: n.type for n in env.network.spec.nodes}["left"] != "traffic_light"
    env.reset(seed=0)
    try:
        env.step(None)
        assert env.k.traffic_light.get_state("top") == "GG"  # SUMO's default program
        env.k.traffic_light.set_state(node_id="top", state="rY")
        env.step(None)
        assert env.k.traffic_light.get_state("top") == "rY"
    finally:
        env.close()


def test_a_light_on_a_node_the_network_lacks_is_still_refused() -> None:
    lights = TrafficLightParams()
    lights.add("nowhere")
    env = ring_with_light(1, lights)
    with pytest.raises(ConfigError, match="no traffic-light junction 'nowhere'"):
        env.reset(seed=0)
    env.close()


def test_the_grid_accepts_and_ignores_the_ring_parameters_of_flows_set_ups() -> None:
    grid = {"short_length": 100, "inner_length": 300, "long_length": 300, "row_num": 1,
            "col_num": 1, "cars_left": 0, "cars_right": 0, "cars_top": 0, "cars_bot": 0}
    params = {"grid_array": grid, "horizontal_lanes": 1, "vertical_lanes": 1}
    plain = TrafficLightGridNetwork("g", VehicleParams(), NetParams(dict(params)))
    extra = TrafficLightGridNetwork(
        "g", VehicleParams(),
        NetParams({**params, "length": 200, "lanes": 2, "resolution": 40}),
    )  # fmt: skip
    assert extra.spec == plain.spec
    with pytest.raises(ConfigError, match="unknown parameter"):
        TrafficLightGridNetwork("g", VehicleParams(), NetParams({**params, "radius": 3}))
