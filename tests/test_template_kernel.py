"""A user's own ``.net.xml`` (Flow's ``NetParams(template=...)``), driven by the kernel:
a subclass that writes only ``specify_routes``, and Flow's ``{net, rou, vtype}`` dict whose
route file brings vehicles of its own type (real SUMO)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from flowrun.config.params import (
    ControllerSpec,
    EnvParams,
    InFlows,
    NetParams,
    SumoParams,
    VehicleParams,
)
from flowrun.networks.base import Network
from flowrun.networks.build import build_network
from tests.test_open_kernel import Drive, ToyMerge

pytestmark = pytest.mark.sumo


class MyCity(Network):
    """Flow's template usage: the road comes from the file, the routes from here."""

    def specify_routes(self, net_params: NetParams) -> dict[str, Any]:
        return {"hw": ["hw", "ce", "out"], "ramp": ["ramp", "ce", "out"]}


@pytest.fixture
def net_file(tmp_path: Path) -> Path:
    toy = ToyMerge("toy", VehicleParams(), NetParams())
    return build_network(toy.spec, tmp_path, name="city")


def humans(count: int = 0) -> VehicleParams:
    vehicles = VehicleParams()
    vehicles.add("human", acceleration_controller=ControllerSpec("IDM", {}), num_vehicles=count)
    return vehicles


def test_a_template_network_with_flows_routes_runs_and_cars_come_and_go(net_file: Path) -> None:
    inflows = InFlows()
    inflows.add("hw", "human", vehs_per_hour=1500, depart_speed=10)
    net = MyCity("city", humans(), NetParams(template=str(net_file), inflows=inflows))
    assert {e.id for e in net.spec.edges} == {"hw", "ramp", "ce", "out"}
    env = Drive(EnvParams(horizon=10**6), SumoParams(sim_step=0.2, seed=0), net)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        arrived = 0
        for _ in range(400):
            env.step(None)
            arrived += vk.get_num_arrived()
            for vid in vk.get_ids():
                found = vk.api.vehicle.getLeader(vid, 500.0)
                assert vk.get_leader(vid) == (found[0] if found and found[0] else None)
        assert arrived > 10
        assert vk.get_route(vk.get_ids()[0]) == ("hw", "ce", "out")
    finally:
        env.close()


def test_vehicles_of_a_templates_own_type_are_left_to_sumo(net_file: Path, tmp_path: Path) -> None:
    rou = tmp_path / "city.rou.xml"
    rou.write_text(
        '<routes><vType id="bus" length="12" maxSpeed="15"/>'
        '<route id="r_bus" edges="ramp ce out"/>'
        '<flow id="buses" type="bus" route="r_bus" begin="0" end="3600" period="20"/></routes>'
    )
    net = MyCity("city", humans(2), NetParams(template={"net": str(net_file), "rou": str(rou)}))
    env = Drive(EnvParams(horizon=10**6), SumoParams(sim_step=0.2, seed=0), net)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        buses: set[str] = set()
        for _ in range(300):
            env.step(None)
            for vid in vk.get_ids():
                if vid.startswith("buses"):
                    buses.add(vid)
                    row = vk.table.row(vid)
                    assert not vk.table.commanded[row]
                    assert np.isnan(vk.last_cmd[row])  # nobody commands a bus
        assert len(buses) >= 3
    finally:
        env.close()
