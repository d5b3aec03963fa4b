"""An inflow may pick one of the network's routes by name, as Flow's
``InFlows.add(..., route="routehighway_0_0")`` does (Flow's multi-agent highway example keeps
its AVs on the highway that way); a wrong name is one located error."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from flowrun.config.params import InFlows, NetParams, VehicleParams
from flowrun.envs.factory import make_env, make_network
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config
from flowrun.networks.highway_ramps import ADDITIONAL_NET_PARAMS, HighwayRampsNetwork
from flowrun.networks.routes import named_routes, routes_xml

CONFIG = """\
name: ramps
sim: {step: 0.5, seed: 2}
env: {class: TestEnv, horizon: 400}
network:
  type: highway_ramps
  highway_length: 600
  on_ramps_pos: []
  off_ramps_pos: [300]
  next_off_ramp_proba: 0.5
  inflows:
    - {edge: highway_0, veh_type: human, vehs_per_hour: 1800, depart_speed: max,
       depart_lane: free, name: human}
    - {edge: highway_0, veh_type: rl, vehs_per_hour: 1800, depart_speed: max,
       depart_lane: free, name: rl, route: ROUTE}
vehicles:
  - {id: human, count: 0, acceleration_controller: {type: IDM}}
  - {id: rl, count: 0, acceleration_controller: {type: IDM}}
"""


def write(tmp_path: Path, route: str, edge: str = "highway_0") -> Path:
    path = tmp_path / "ramps.yaml"
    text = CONFIG.replace("ROUTE", route)
    if edge != "highway_0":
        text = text.replace("- {edge: highway_0, veh_type: rl", f"- {{edge: {edge}, veh_type: rl")
    path.write_text(textwrap.dedent(text))
    return path


def network_with_rl_route(route: str) -> HighwayRampsNetwork:
    params = {**ADDITIONAL_NET_PARAMS, "off_ramps_pos": [300], "highway_length": 600}
    inflows = InFlows()
    inflows.add(veh_type="human", edge="highway_0", vehs_per_hour=1000, name="idm")
    inflows.add(veh_type="rl", edge="highway_0", vehs_per_hour=200, name="rl", route=route)
    return HighwayRampsNetwork(
        "ramps", VehicleParams(), NetParams(additional_params=params, inflows=inflows)
    )


def test_flows_names_pick_a_route_in_flows_order() -> None:
    network = network_with_rl_route("routehighway_0_0")
    names = named_routes(network.spec)
    # Flow's order: staying on the highway is choice 0, leaving at the ramp choice 1
    assert network.spec.choices("highway_0")[0][0] == ("highway_0", "highway_1")
    assert names["routehighway_0_0"] == ("highway_0", 0)
    assert names["routehighway_0_1"] == ("highway_0", 1)
    xml = routes_xml(network.spec, network.vehicles, network.net_params.inflows)
    flows = [line.strip() for line in xml.splitlines() if "<flow " in line]
    human = [f for f in flows if 'type="human"' in f]
    rl = [f for f in flows if 'type="rl"' in f]
    assert len(human) == 2  # spread over both choices
    assert rl == [f for f in rl if 'route="route_highway_0_0"' in f and 'vehsPerHour="200.0"' in f]
    assert len(rl) == 1  # one flow, the whole rate, on the chosen route


def test_the_route_is_a_field_of_the_inflow_not_an_extra_attribute() -> None:
    inflows = InFlows()
    inflows.add(veh_type="rl", edge="highway_0", vehs_per_hour=200, route="routehighway_0_0")
    (flow,) = inflows.get()
    assert flow.route == "routehighway_0_0" and "route" not in flow.extra


def test_an_unknown_route_is_refused_at_its_line(tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(write(tmp_path, "routehighway_0_3"))
    err = info.value
    assert err.path == "network.inflows[1].route"
    assert err.location.endswith("ramps.yaml:14")  # the inflow's line
    assert "did you mean 'routehighway_0_0'" in err.message or "routehighway_0_1" in err.message


def test_a_route_that_starts_elsewhere_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="starts on edge 'highway_0' but the inflow enters"):
        load_config(write(tmp_path, "routehighway_0_0", edge="highway_1"))


@pytest.mark.sumo
def test_vehicles_of_a_routed_inflow_never_take_the_ramp(tmp_path: Path) -> None:
    cfg = load_config(write(tmp_path, "routehighway_0_0"))
    assert make_network(cfg).net_params.inflows.get()[1].route == "routehighway_0_0"
    env = make_env(cfg)
    edges: dict[str, set[str]] = {"human": set(), "rl": set()}
    try:
        env.reset(seed=0)
        for _ in range(300):
            env.step(None)
            for vid in env.k.vehicle.get_ids():
                edges[env.k.vehicle.get_type(vid)].add(env.k.vehicle.get_edge(vid))
    finally:
        env.close()
    assert "off_ramp_0" in edges["human"]  # half the humans leave (the route is a real choice)
    assert "off_ramp_0" not in edges["rl"] and "highway_1" in edges["rl"]
