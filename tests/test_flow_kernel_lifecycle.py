"""Flow's manual kernel lifecycle (``flowrun.core.kernel.Kernel``) over flowrun's kernel:
generate the network, start SUMO (one step on the empty network, as Flow's), tear it down."""

from __future__ import annotations

from pathlib import Path

import pytest

from flowrun.config.params import InFlows, NetParams, SumoParams, VehicleParams
from flowrun.core.kernel import Kernel
from flowrun.errors import ConfigError, SimulationError
from flowrun.kernel.sumo import SumoProcess
from flowrun.networks.merge import MergeNetwork
from flowrun.networks.ring import RingNetwork

pytestmark = pytest.mark.sumo

RING = {"length": 230, "lanes": 1, "speed_limit": 30, "resolution": 40}


def test_generate_start_and_teardown_as_flow() -> None:
    k = Kernel("traci", SumoParams(sim_step=0.1))
    try:
        k.network.generate_network(RingNetwork("ring", VehicleParams(), NetParams(RING)))
        assert k.network.length() == pytest.approx(230.0)  # getters right after generating
        api = k.simulation.start_simulation(network=k.network, sim_params=k.sim_params)
        assert isinstance(k.simulation.sumo_proc, SumoProcess)  # the in-process simulation
        assert api is k.kernel_api and api.simulation.getTime() == pytest.approx(0.1)
        assert set(api.edge.getIDList()) >= {"bottom", "right", "top", "left"}
        k.simulation.simulation_step()
        assert api.simulation.getTime() == pytest.approx(0.2)
        k.simulation.teardown_sumo()
        assert k.simulation.sumo_proc is None and k.kernel_api is None
        k.simulation.teardown_sumo()  # safe twice
        with pytest.raises(SimulationError, match="start_simulation"):
            k.simulation.simulation_step()
    finally:
        k.close()
    assert not k.work_dir.exists()


def test_the_generated_files_hold_the_inflows() -> None:
    vehicles = VehicleParams()
    vehicles.add("human", num_vehicles=0)
    inflows = InFlows()
    inflows.add("inflow_highway", "human", vehs_per_hour=3600, depart_speed=10)
    k = Kernel("traci", SumoParams(sim_step=0.5))
    try:
        k.network.generate_network(MergeNetwork("m", vehicles, NetParams(inflows=inflows)))
        api = k.simulation.start_simulation(network=k.network, sim_params=k.sim_params)
        for _ in range(6):
            k.simulation.simulation_step()
        assert api.simulation.getTime() == pytest.approx(3.5)
        assert api.vehicle.getIDList()[:2] == ("flow_0.0", "flow_0.1")  # the inflow's cars
    finally:
        k.close()


def test_lifecycle_misuse_is_refused() -> None:
    with pytest.raises(ConfigError, match="flowrun drives SUMO only"):
        Kernel("aimsun", SumoParams())
    k = Kernel("traci", SumoParams())
    try:
        with pytest.raises(ConfigError, match="generate_network"):
            k.simulation.start_simulation()
        with pytest.raises(AttributeError, match="generate_network"):
            k.network.length()
    finally:
        k.close()


def test_a_template_dicts_rou_routes_are_flows_network_routes(tmp_path: Path) -> None:
    from flowrun.networks.base import Network
    from flowrun.networks.build import build_network
    from tests.test_open_kernel import ToyMerge

    net_file = build_network(ToyMerge("toy", VehicleParams(), NetParams()).spec, tmp_path, "t")
    rou = tmp_path / "t.rou.xml"
    rou.write_text(
        '<routes>\n  <route id="main" edges="hw ce out"/>\n'
        '  <vehicle id="v0" depart="0"><route edges="ramp ce out"/></vehicle>\n</routes>\n'
    )
    plain = Network("plain", VehicleParams(), NetParams(template=str(net_file)))
    assert plain.routes["hw"] == [(["hw"], 1.0)]  # without a rou file: {start edge: [(r, p)]}
    net = Network("t", VehicleParams(), NetParams(template={"net": str(net_file),
                                                            "rou": str(rou)}))  # fmt: skip
    # Flow's network.routes of a template with a rou file: that file's routes by id
    assert net.routes == {"main": ["hw", "ce", "out"], "v0": ["ramp", "ce", "out"]}
