"""Flow's I-210 sub-network on a template: Flow's routes and main-highway positions over a
small stand-in for the I-210 file (same edge ids and topology, built here with
netconvert), driven on real SUMO."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from flowrun.config.inflows import InFlows
from flowrun.config.params import EnvParams, InitialConfig, NetParams, SumoParams, VehicleParams
from flowrun.envs import TestEnv
from flowrun.errors import ConfigError
from flowrun.networks import I210SubNetwork
from flowrun.networks.base import Edge, NetworkSpec, Node
from flowrun.networks.build import build_network
from flowrun.networks.i210_subnetwork import LENGTH_WITH_GHOST_EDGE, MAIN, i210_routes
from flowrun.networks.registry import network_class


def stand_in(tmp_path: Path) -> Path:
    """A straight main highway with Flow's I-210 edge ids and lengths, the on-ramp joining
    at ``119257908#1-AddedOnRampEdge`` and the off-ramp leaving after
    ``119257908#1-AddedOffRampEdge``."""
    lengths = dict(LENGTH_WITH_GHOST_EDGE)
    xs = [0.0, *itertools.accumulate(lengths[e] + 10.0 for e in MAIN)]
    nodes = [Node(f"m{i}", x, 0.0) for i, x in enumerate(xs)]
    edges = [Edge(e, f"m{i}", f"m{i + 1}", lengths[e], 3, 30.0) for i, e in enumerate(MAIN)]
    merge = MAIN.index("119257908#1-AddedOnRampEdge")
    leave = MAIN.index("119257908#1-AddedOffRampEdge") + 1
    x0 = xs[merge]
    nodes += [Node("r0", x0 - 300, -120), Node("r0b", x0 - 300, -60), Node("r1", x0 - 200, -80),
              Node("r2", x0 - 100, -40), Node("off", xs[leave] + 100, -60)]  # fmt: skip
    edges += [Edge("27414345", "r0", "r1", 100.0, 1, 20.0),
              Edge("27414342#0", "r0b", "r1", 100.0, 1, 20.0),
              Edge("27414342#1-AddedOnRampEdge", "r1", "r2", 100.0, 1, 20.0),
              Edge("27414342#1", "r2", f"m{merge}", 100.0, 1, 20.0),
              Edge("173381935", f"m{leave}", "off", 100.0, 1, 20.0)]  # fmt: skip
    spec = NetworkSpec(tuple(nodes), tuple(edges), {}, {}, 0.0, internal_links=True)
    return build_network(spec, tmp_path, "i210")


def test_flow_routes_and_parameters() -> None:
    routes = i210_routes(on_ramp=False, ghost_edge=True)
    assert set(routes) == {"ghost0", "119257914"}
    assert routes["ghost0"] == [(list(MAIN), 1.0)]
    ramp = i210_routes(on_ramp=True, ghost_edge=False)["27414345"]
    assert [q for _, q in ramp] == pytest.approx([1 - 9 / 321, 9 / 321])
    assert ramp[1][0][-2:] == ["119257908#1-AddedOffRampEdge", "173381935"]
    assert ramp[0][0][:4] == ["27414345", "27414342#1-AddedOnRampEdge", "27414342#1",
                              "119257908#1-AddedOnRampEdge"]  # fmt: skip
    assert network_class("I210SubNetwork") is I210SubNetwork
    with pytest.raises(ConfigError, match="true or false"):
        I210SubNetwork.resolve_params({"on_ramp": "yes"})
    with pytest.raises(ConfigError, match="unknown parameter"):
        I210SubNetwork.resolve_params({"routes": {}})


def test_cars_drive_flows_routes_on_the_template(tmp_path: Path) -> None:
    inflows = InFlows()
    inflows.add(edge="119257914", veh_type="human", vehs_per_hour=1800, depart_lane="free",
                depart_speed=20)  # fmt: skip
    inflows.add(edge="27414342#1-AddedOnRampEdge", veh_type="human", vehs_per_hour=600,
                depart_lane="free", depart_speed=10)  # fmt: skip
    vehicles = VehicleParams()
    vehicles.add("human", num_vehicles=0)
    net = NetParams(additional_params={"on_ramp": True, "ghost_edge": True},
                    template=str(stand_in(tmp_path)), inflows=inflows)  # fmt: skip
    network = I210SubNetwork("i210", vehicles, net, InitialConfig())
    starts = network.spec.edge_starts
    assert starts["119257914"] == pytest.approx(573.08 + 0.30)  # Flow's positions
    assert starts["119257908#3"] == pytest.approx(sum(v for _, v in LENGTH_WITH_GHOST_EDGE[:-1]))
    env = TestEnv(EnvParams(horizon=1200), SumoParams(sim_step=0.5), network)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        last: dict[str, str] = {}
        for _ in range(1200):
            env.step(None)
            for vid in vk.get_departed_ids():
                last[vid] = vk.get_route(vid)[-1]
        assert env.k.simulation.collisions == 0
    finally:
        env.close()
    main = [e for v, e in last.items() if v.startswith("flow_0")]
    ramp = [e for v, e in last.items() if v.startswith("flow_1")]
    assert len(main) > 200 and set(main) == {"119257908#3"}
    # Flow: half of the cars entering on 27414342#1-AddedOnRampEdge take the off-ramp
    assert np.mean([e == "173381935" for e in ramp]) == pytest.approx(0.5, abs=0.15)
