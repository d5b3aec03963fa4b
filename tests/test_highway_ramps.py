"""Flow's highway with on- and off-ramps on real SUMO: geometry, Flow's route choices
(``next_off_ramp_proba``), bad parameters, and the share of cars that take the off-ramp."""

from __future__ import annotations

import itertools
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from flowrun.config.params import InitialConfig, NetParams, VehicleParams
from flowrun.envs.factory import make_env
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config
from flowrun.networks import HighwayRampsNetwork
from flowrun.networks.build import build_network
from flowrun.networks.highway_ramps import ramp_routes
from flowrun.networks.registry import network_class

CONFIG = Path(__file__).resolve().parent.parent / "configs" / "highway_ramps.yaml"


def make(**params: object) -> HighwayRampsNetwork:
    net = NetParams(additional_params=dict(params))
    return HighwayRampsNetwork("h", VehicleParams(), net, InitialConfig())


@pytest.mark.parametrize(("ramp_lanes", "angle"), [(1, -3 * math.pi / 4), (2, -math.pi / 8)])
def test_every_route_is_driveable_with_flows_names(
    tmp_path: Path, ramp_lanes: int, angle: float
) -> None:
    net = make(highway_length=1200, highway_lanes=3, on_ramps_pos=[400], off_ramps_pos=[800],
               on_ramps_lanes=ramp_lanes, angle_on_ramps=angle)  # fmt: skip
    root = ET.parse(build_network(net.spec, tmp_path, "highway_ramps")).getroot()
    edges = {e.get("id"): len(e.findall("lane")) for e in root.iter("edge")
             if e.get("function") != "internal"}  # fmt: skip
    assert edges == {"highway_0": 3, "highway_1": 3, "highway_2": 3, "on_ramp_0": ramp_lanes,
                     "off_ramp_0": 1}  # fmt: skip
    links = {(c.get("from"), c.get("to")) for c in root.iter("connection")}
    kinds = {j.get("id"): j.get("type") for j in root.iter("junction")}
    assert kinds["highway_1"] == "zipper" and kinds["highway_2"] == "priority"
    for choices in net.spec.route_choices.values():
        assert sum(q for _, q in choices) == pytest.approx(1.0)
        for route, _ in choices:
            assert all(pair in links for pair in itertools.pairwise(route)), route
    assert network_class("HighwayRampsScenario") is HighwayRampsNetwork
    # positions run on along the highway: each edge starts where the one before and the
    # link SUMO built through the junction end
    starts = net.spec.edge_starts
    link = {lane.get("id"): float(lane.get("length", "nan"))
            for e in root.iter("edge") if e.get("function") == "internal"
            for lane in e.findall("lane")}  # fmt: skip
    on_highway = ("highway", "highway")
    through = [
        c
        for c in root.iter("connection")
        if c.get("via") and (c.get("from", "")[:7], c.get("to", "")[:7]) == on_highway
    ]
    assert len(through) == 2 * 3
    for c in through:
        a, b = c.get("from", ""), c.get("to", "")
        length = next(e.length for e in net.spec.edges if e.id == a)
        assert starts[b] == pytest.approx(starts[a] + length + link[c.get("via", "")], abs=1e-3)


def test_route_probabilities_multiply_at_each_off_ramp() -> None:
    # nodes 1 and 3 are off-ramps, node 2 an on-ramp; 4 highway edges
    choices = ramp_routes(4, {1: "off_ramp_0", 2: "on_ramp_0", 3: "off_ramp_1"}, 0.25)
    got = {route: q for route, q in choices["highway_0"]}
    assert got == pytest.approx({
        ("highway_0", "off_ramp_0"): 0.25,
        ("highway_0", "highway_1", "highway_2", "off_ramp_1"): 0.75 * 0.25,
        ("highway_0", "highway_1", "highway_2", "highway_3"): 0.75 * 0.75,
    })  # fmt: skip
    ramp = {route: q for route, q in choices["on_ramp_0"]}
    assert ramp == pytest.approx({
        ("on_ramp_0", "highway_2", "off_ramp_1"): 0.25,
        ("on_ramp_0", "highway_2", "highway_3"): 0.75,
    })  # fmt: skip
    assert choices["off_ramp_0"] == ((("off_ramp_0",), 1.0),)


@pytest.mark.parametrize(
    ("params", "match"),
    [
        ({"on_ramps_pos": [0]}, "strictly inside"),
        ({"off_ramps_pos": [300]}, "strictly inside"),
        ({"on_ramps_pos": [100], "off_ramps_pos": [100]}, "share a position"),
        ({"next_off_ramp_proba": 1.5}, "probability"),
        ({"highway_lanes": 0}, "integer >= 1"),
    ],
)
def test_bad_ramps_are_refused(params: dict[str, object], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        make(**params)


def test_a_quarter_of_the_highway_cars_take_the_off_ramp() -> None:
    steps = 1500  # 300 s of 0.2 s steps
    cfg = load_config(CONFIG, ["env.sims_per_step=1", f"env.horizon={steps}"])
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        last_edge: dict[str, str] = {}
        arrived: list[str] = []
        x_prev: dict[str, tuple[float, float]] = {}
        for _ in range(steps):
            _, _, terminated, _, info = env.step(None)
            assert not terminated
            arrived += vk.get_arrived_ids()
            for vid in vk.get_departed_ids():
                last_edge[vid] = vk.get_route(vid)[-1]
            for vid in vk.get_ids():
                x, odo = vk.get_x_by_id(vid), vk.get_distance(vid)
                on_highway = vk.get_edge(vid).startswith(("highway", ":highway"))
                if vid in x_prev and vid.startswith("highway_flow") and on_highway:
                    dx, dd = x - x_prev[vid][0], odo - x_prev[vid][1]
                    assert dx == pytest.approx(dd, abs=0.01)  # as far as the car drove
                x_prev[vid] = (x, odo)
        assert info["collisions"] == 0
    finally:
        env.close()
    highway = [e for v, e in last_edge.items() if v.startswith("highway_flow")]
    ramp = [e for v, e in last_edge.items() if v.startswith("on_ramp_flow")]
    assert len(highway) > 250 and len(ramp) > 20
    # ramp cars merge (the zipper lets them in) and drive on to the end
    assert sum(v.startswith("on_ramp_flow") for v in arrived) > 10
    share = np.mean([e == "off_ramp_0" for e in highway + ramp])
    assert share == pytest.approx(0.25, abs=0.06)
