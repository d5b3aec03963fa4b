"""Flow's highway as Flow's own set-ups use it: a ring's ``resolution`` key is accepted and
unused, ``spacing="custom"`` places cars where ``initial_config.additional_params`` says, and
a start SUMO cannot honour raises Flow's ``FatalFlowError`` (real SUMO)."""

from __future__ import annotations

import pytest

from flowrun.controllers import IDMController
from flowrun.core.params import EnvParams, InitialConfig, NetParams, SumoParams, VehicleParams
from flowrun.envs.ring.accel import ADDITIONAL_ENV_PARAMS, AccelEnv
from flowrun.errors import ConfigError, FatalFlowError, FlowrunError, SimulationError
from flowrun.networks import HighwayNetwork
from flowrun.utils.exceptions import FatalFlowError as UtilsFatalFlowError


def highway(initial: InitialConfig, n: int = 2, **params: object) -> HighwayNetwork:
    vehicles = VehicleParams()
    vehicles.add("test", acceleration_controller=(IDMController, {}), num_vehicles=n)
    net = NetParams(additional_params={"length": 100, "lanes": 2, "num_edges": 1, **params})
    return HighwayNetwork("hw", vehicles, net, initial)


def env_on(network: HighwayNetwork) -> AccelEnv:
    return AccelEnv(EnvParams(additional_params=ADDITIONAL_ENV_PARAMS), SumoParams(), network)


def test_resolution_is_accepted_and_changes_nothing() -> None:
    with_res = highway(InitialConfig(), resolution=40)
    plain = highway(InitialConfig())
    assert "resolution" not in with_res.params
    assert with_res.spec.length == pytest.approx(plain.spec.length)


def test_other_unknown_highway_keys_are_still_refused() -> None:
    with pytest.raises(ConfigError, match="lenght"):
        highway(InitialConfig(), lenght=40)


def test_custom_spacing_puts_cars_where_listed() -> None:
    initial = InitialConfig(
        spacing="custom",
        additional_params={
            "start_positions": [("highway_0", 10.0), ("highway_0", 40.0)],
            "start_lanes": [1, 0],
        },
    )
    env = env_on(highway(initial))
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        assert vk.get_position("test_0") == pytest.approx(10.0)
        assert vk.get_position("test_1") == pytest.approx(40.0)
        assert [vk.get_lane("test_0"), vk.get_lane("test_1")] == [1, 0]
    finally:
        env.close()


def test_custom_spacing_without_the_lists_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match="start_lanes"):
        highway(
            InitialConfig(spacing="custom", additional_params={"start_positions": []})
        ).start_positions(None)  # type: ignore[arg-type]


def test_two_cars_on_one_spot_raise_flows_fatal_error() -> None:
    initial = InitialConfig(
        spacing="custom",
        additional_params={
            "start_positions": [("highway_0", 0), ("highway_0", 0)],
            "start_lanes": [0, 0],
        },
    )
    env = env_on(highway(initial))
    try:
        with pytest.raises(FatalFlowError, match="could not insert 1 of 2"):
            env.reset(seed=0)
    finally:
        env.close()


def test_fatal_flow_error_is_one_class_in_flowruns_hierarchy() -> None:
    assert UtilsFatalFlowError is FatalFlowError
    assert issubclass(SimulationError, FatalFlowError)
    assert issubclass(FatalFlowError, FlowrunError)
    assert FatalFlowError("bad start").message == "bad start"
