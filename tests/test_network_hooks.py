"""A network written Flow's way (``specify_nodes``/``specify_edges``/``specify_routes``...)
builds exactly that road, and the kernel drives it (real SUMO)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from flowrun.config.params import (
    ControllerSpec,
    EnvParams,
    InitialConfig,
    NetParams,
    SumoParams,
    VehicleParams,
)
from flowrun.errors import ConfigError
from flowrun.networks.base import Network
from tests.test_open_kernel import Drive

R = 40.0  # radius, m


class MyRing(Network):
    """Flow's tutorial network: a ring of four quarter-circle edges."""

    def specify_nodes(self, net_params: NetParams) -> list[dict[str, Any]]:
        return [{"id": "bottom", "x": 0, "y": -R}, {"id": "right", "x": R, "y": 0},
                {"id": "top", "x": 0, "y": R}, {"id": "left", "x": -R, "y": 0}]  # fmt: skip

    def specify_edges(self, net_params: NetParams) -> list[dict[str, Any]]:
        lanes = net_params.additional_params.get("lanes", 1)

        def arc(a0: float) -> list[tuple[float, float]]:
            t = np.linspace(a0, a0 + np.pi / 2, 20)
            return [(R * np.cos(x), R * np.sin(x)) for x in t]

        names = ["bottom", "right", "top", "left"]
        return [
            {"id": f"edge{i}", "numLanes": lanes, "speed": 30, "from": names[i],
             "to": names[(i + 1) % 4], "length": np.pi * R / 2,
             "shape": arc(-np.pi / 2 + i * np.pi / 2)}
            for i in range(4)
        ]  # fmt: skip

    def specify_routes(self, net_params: NetParams) -> dict[str, Any]:
        loop = ["edge0", "edge1", "edge2", "edge3"]
        return {f"edge{i}": loop[i:] + loop[:i] for i in range(4)}


def env_on(network_cls: type[Network], n: int = 11) -> Drive:
    vehicles = VehicleParams()
    vehicles.add("human", acceleration_controller=ControllerSpec("IDM", {}),
                 routing_controller=ControllerSpec("ContinuousRouter"), num_vehicles=n)  # fmt: skip
    net = network_cls("my_ring", vehicles, NetParams(additional_params={"lanes": 1}),
                      InitialConfig(bunching=20))  # fmt: skip
    return Drive(EnvParams(horizon=5000), SumoParams(sim_step=0.1, seed=0), net)


def test_the_specified_edges_routes_and_starts_become_the_spec() -> None:
    env = env_on(MyRing)
    try:
        spec = env.network.spec
        assert [e.id for e in spec.edges] == ["edge0", "edge1", "edge2", "edge3"]
        assert spec.routes["edge2"] == ("edge2", "edge3", "edge0", "edge1")
        assert spec.edge_starts["edge1"] == pytest.approx(np.pi * R / 2)
        assert spec.length == pytest.approx(2 * np.pi * R)
    finally:
        env.close()


@pytest.mark.sumo
def test_cars_circle_the_user_ring_forever_with_leaders_all_round() -> None:
    env = env_on(MyRing)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        assert vk.api.lane.getLength("edge0_0") == pytest.approx(np.pi * R / 2, abs=0.01)
        for _ in range(1500):  # several laps
            env.step(None)
            assert len(vk.get_ids()) == 11
            assert not vk.get_arrived_ids()
        assert np.isfinite(vk.headway).all()  # every car has a leader on a closed loop
        assert vk.odometer.min() > 2 * np.pi * R  # at least a lap each
        for vid in vk.get_ids():
            found = vk.api.vehicle.getLeader(vid, 500.0)
            assert vk.get_leader(vid) == found[0]
    finally:
        env.close()


def test_a_network_class_without_a_road_is_a_clear_error() -> None:
    class Empty(Network):
        pass

    with pytest.raises(ConfigError, match="describes no road: implement Flow's specify_nodes"):
        env_on(Empty)


def test_a_route_through_an_unknown_edge_is_refused() -> None:
    class Bad(MyRing):
        def specify_routes(self, net_params: NetParams) -> dict[str, Any]:
            return {"edge0": ["edge0", "edge9"]}

    with pytest.raises(ConfigError, match=r"no edge 'edge9' in Bad\.specify_routes"):
        env_on(Bad)


def test_an_edges_spread_type_is_kept_and_an_unknown_one_refused() -> None:
    class Centred(MyRing):
        def specify_edges(self, net_params: NetParams) -> list[dict[str, Any]]:
            return [{**e, "spreadType": "center"} for e in super().specify_edges(net_params)]

    env = env_on(Centred)
    try:
        assert {e.spread_type for e in env.network.spec.edges} == {"center"}
        assert {e["spreadType"] for e in env.network.edges} == {"center"}  # Flow's view
    finally:
        env.close()

    class Bad(MyRing):
        def specify_edges(self, net_params: NetParams) -> list[dict[str, Any]]:
            return [{**e, "spreadType": "centre"} for e in super().specify_edges(net_params)]

    with pytest.raises(ConfigError, match=r"spreadType 'centre' \(did you mean 'center'\?\)"):
        env_on(Bad)
