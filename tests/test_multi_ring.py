"""Flow's ``MultiRingNetwork``: ``num_rings`` separate rings in one simulation; each ring gets
its share of the cars, which circle their own ring only (real SUMO)."""

from __future__ import annotations

import numpy as np
import pytest

from flowrun.controllers import ContinuousRouter, IDMController
from flowrun.core.params import NetParams, VehicleParams
from flowrun.networks import MultiRingNetwork
from flowrun.networks.multi_ring import ADDITIONAL_NET_PARAMS
from flowrun.networks.registry import network_class
from flowrun.utils.registry import env_constructor
from tests.test_flow_params import ring_params


def network(rings: int = 3, n: int = 6) -> MultiRingNetwork:
    vehicles = VehicleParams()
    vehicles.add(veh_id="idm", acceleration_controller=(IDMController, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=n)  # fmt: skip
    params = dict(ADDITIONAL_NET_PARAMS, num_rings=rings)
    return MultiRingNetwork("lotr", vehicles, NetParams(additional_params=params))


def test_rings_are_flows_four_edges_each_with_flows_edge_starts() -> None:
    net = network()
    assert network_class("MultiRingNetwork") is MultiRingNetwork
    assert [e.id for e in net.spec.edges][:5] == ["bottom_0", "right_0", "top_0", "left_0",
                                                  "bottom_1"]  # fmt: skip
    assert net.spec.edge_starts["top_2"] == pytest.approx(2 * 230 + 115)
    assert net.spec.routes["left_1"] == ("left_1", "bottom_1", "right_1", "top_1")
    assert net.spec.length == pytest.approx(3 * 230)
    xs = {round(n.x, 6) for n in net.spec.nodes}
    assert len(xs) > 3  # the rings stand apart, not on top of each other


def test_each_ring_gets_its_share_of_the_cars() -> None:
    start = network(rings=3, n=7).start_positions(np.random.default_rng(0))
    rings = [int(e.rsplit("_", 1)[1]) for e in start.edges]
    assert [rings.count(i) for i in range(3)] == [3, 2, 2]


@pytest.mark.sumo
def test_cars_circle_their_own_ring() -> None:
    vehicles = VehicleParams()
    vehicles.add(veh_id="idm", acceleration_controller=(IDMController, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=8)  # fmt: skip
    params = ring_params(
        network=MultiRingNetwork, veh=vehicles,
        net=NetParams(additional_params=dict(ADDITIONAL_NET_PARAMS, num_rings=4)),
    )  # fmt: skip
    env = env_constructor(params)()
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        home = {v: vk.get_edge(v).rsplit("_", 1)[1] for v in vk.get_ids()}
        seen: dict[str, set[str]] = {v: set() for v in home}
        for _ in range(200):
            _, _, terminated, _, _ = env.step(None)
            assert not terminated
            for v in vk.get_ids():
                edge = vk.get_edge(v)
                if not edge.startswith(":"):
                    assert edge.rsplit("_", 1)[1] == home[v]
                    seen[v].add(edge)
        assert sorted(home.values()) == ["0", "0", "1", "1", "2", "2", "3", "3"]
        assert all(len(edges) == 4 for edges in seen.values())  # all the way round
    finally:
        env.close()
