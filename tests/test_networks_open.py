"""Flow's open networks (figure eight, merge, highway, template/OSM): the SUMO networks that
netconvert builds from them, their names, lengths and routes, and bad input."""

from __future__ import annotations

import itertools
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from flowrun.config.params import InitialConfig, NetParams, VehicleParams
from flowrun.errors import ConfigError
from flowrun.networks import FigureEightNetwork, HighwayNetwork, MergeNetwork, TemplateNetwork
from flowrun.networks.base import Network, NetworkSpec
from flowrun.networks.build import build_network, connections_xml, nodes_xml
from flowrun.networks.registry import network_class, network_table, validate_network
from flowrun.networks.ring import RingNetwork
from flowrun.networks.template_read import convert_osm


def make(cls: type[Network], template: str | dict[str, str] | None = None,
         osm: str | None = None, **params: object) -> Network:  # fmt: skip
    net = NetParams(additional_params=dict(params), template=template, osm_path=osm)  # type: ignore[arg-type]
    return cls("test", VehicleParams(), net, InitialConfig())


def read_built(net_file: Path) -> tuple[dict[str, list[ET.Element]], set[tuple[str, str]]]:
    """Non-internal edges -> their lanes, and the (from, to) edge connections of a net file."""
    root = ET.parse(net_file).getroot()
    edges = {
        e.get("id", ""): e.findall("lane")
        for e in root.iter("edge")
        if e.get("function") != "internal"
    }
    links = {(c.get("from", ""), c.get("to", "")) for c in root.iter("connection")}
    return edges, links


def internal_edges(net_file: Path) -> set[str]:
    root = ET.parse(net_file).getroot()
    return {e.get("id", "") for e in root.iter("edge") if e.get("function") == "internal"}


def check_built(spec: NetworkSpec, net_file: Path) -> None:
    """Edges as declared (names, lanes, lengths to 0.1 m) and every route connected."""
    edges, links = read_built(net_file)
    assert sorted(edges) == sorted(e.id for e in spec.edges)
    for e in spec.edges:
        assert len(edges[e.id]) == e.lanes
        for lane in edges[e.id]:
            assert float(lane.get("length", "nan")) == pytest.approx(e.length, abs=0.1)
            assert float(lane.get("speed", "nan")) == pytest.approx(e.speed, abs=1e-6)
    for route in spec.routes.values():
        for a, b in itertools.pairwise(route):
            assert (a, b) in links, f"{a} -> {b} not connected"
    assert spec.internal_links
    assert set(spec.main_route) <= set(edges)


# --- figure eight --------------------------------------------------------------------------


@pytest.mark.parametrize("lanes", [1, 2])
def test_figure_eight_builds_flows_edges_with_a_priority_crossing(
    tmp_path: Path, lanes: int
) -> None:
    network = make(FigureEightNetwork, lanes=lanes)
    spec = network.spec
    net = build_network(spec, tmp_path, "figure_eight")
    check_built(spec, net)
    r = 30.0
    assert network.length == pytest.approx(4 * r + 3 * math.pi * r)
    assert {e.id: e.length for e in spec.edges}["upper_ring"] == pytest.approx(1.5 * math.pi * r)
    root = ET.parse(net).getroot()
    center = next(j for j in root.iter("junction") if j.get("id") == "center")
    assert center.get("type") == "priority"
    _, links = read_built(net)
    # only straight through the crossing: no turn from bottom into left, nor right into top
    assert ("bottom", "left") not in links and ("right", "top") not in links
    # bottom/top (78) have right of way over right/left (46): the right -> left link yields
    cross = {(c.get("from"), c.get("to")): c.get("state") for c in root.iter("connection")}
    assert cross[("bottom", "top")] == "M" and cross[("right", "left")] == "m"
    # Flow's internal edge starts name SUMO's actual internal edges
    internal = {e for e in spec.edge_starts if e.startswith(":")}
    assert internal <= internal_edges(net)
    assert spec.routes["bottom"] == ("bottom", "top", "upper_ring", "right", "left", "lower_ring")
    assert not spec.closed


def test_figure_eight_node_radius_and_connections_reach_netconvert() -> None:
    spec = make(FigureEightNetwork, lanes=2).spec
    assert 'id="center" x="0.000000" y="0.000000" type="priority" radius="4.750000"' in nodes_xml(
        spec
    )
    con = connections_xml(spec)
    assert con.count("<connection ") == 4
    assert 'from="right" to="left" fromLane="1" toLane="1"' in con


# --- merge ---------------------------------------------------------------------------------


@pytest.mark.parametrize(("merge_lanes", "highway_lanes"), [(1, 1), (2, 3)])
def test_merge_builds_flows_edges_lengths_and_routes(
    tmp_path: Path, merge_lanes: int, highway_lanes: int
) -> None:
    network = make(
        MergeNetwork, pre_merge_length=500, merge_lanes=merge_lanes, highway_lanes=highway_lanes
    )
    spec = network.spec
    net = build_network(spec, tmp_path, "merge")
    check_built(spec, net)
    lengths = {e.id: e.length for e in spec.edges}
    assert lengths == {"inflow_highway": 100, "left": 500, "center": 100,
                       "inflow_merge": 100, "bottom": 100}  # fmt: skip
    assert spec.routes == {
        "inflow_highway": ("inflow_highway", "left", "center"),
        "left": ("left", "center"),
        "center": ("center",),
        "inflow_merge": ("inflow_merge", "bottom", "center"),
        "bottom": ("bottom", "center"),
    }
    assert spec.main_route == ("inflow_highway", "left", "center")
    assert {e for e in spec.edge_starts if e.startswith(":")} <= internal_edges(net)
    # the ramp meets the highway at 45 degrees
    nodes = {n.id: n for n in spec.nodes}
    dx = nodes["center"].x - nodes["bottom"].x
    dy = nodes["center"].y - nodes["bottom"].y
    assert math.degrees(math.atan2(dy, dx)) == pytest.approx(45.0)


# --- highway -------------------------------------------------------------------------------


@pytest.mark.parametrize(("num_edges", "ghost"), [(1, False), (3, True)])
def test_highway_builds_its_edges_and_the_ghost_edge(
    tmp_path: Path, num_edges: int, ghost: bool
) -> None:
    params = {"length": 900, "lanes": 2, "num_edges": num_edges, "use_ghost_edge": ghost,
              "ghost_speed_limit": 10, "boundary_cell_length": 300}  # fmt: skip
    network = HighwayNetwork("test", VehicleParams(), NetParams(additional_params=params))
    spec = network.spec
    net = build_network(spec, tmp_path, "highway")
    check_built(spec, net)
    names = [f"highway_{i}" for i in range(num_edges)] + (["highway_end"] if ghost else [])
    assert [e.id for e in spec.edges] == names
    assert spec.routes["highway_0"] == tuple(names)
    assert spec.main_route == tuple(names)
    if ghost:
        end = spec.edges[-1]
        assert (end.length, end.speed) == (300, 10)
        assert network.length == pytest.approx(1200)
        assert spec.edge_starts["highway_end"] == pytest.approx(900 + 3 * 0.1)
    assert {e for e in spec.edge_starts if e.startswith(":")} <= internal_edges(net)


# --- parameters and the registry -----------------------------------------------------------


def test_unknown_network_parameter_is_an_error_with_a_suggestion() -> None:
    with pytest.raises(ConfigError, match="did you mean 'radius_ring'") as err:
        make(FigureEightNetwork, ring_radius=50)
    assert err.value.path == "ring_radius"
    with pytest.raises(ConfigError, match="did you mean 'pre_merge_length'"):
        validate_network("merge", {"premerge_length": 1}, VehicleParams(), InitialConfig())


@pytest.mark.parametrize(
    ("kind", "params", "key"),
    [
        ("highway", {"lanes": 0}, "lanes"),
        ("highway", {"use_ghost_edge": "yes"}, "use_ghost_edge"),
        ("merge", {"merge_length": -5}, "merge_length"),
        ("figure_eight", {"resolution": 1}, "resolution"),
        ("template", {"routes": ["a"]}, "routes"),
    ],
)
def test_bad_parameter_values_name_the_key(kind: str, params: dict[str, object], key: str) -> None:
    with pytest.raises(ConfigError) as err:
        validate_network(kind, params, VehicleParams(), InitialConfig())
    assert err.value.path == key


def test_registry_knows_flows_class_names_and_lists_parameters() -> None:
    assert network_class("MergeScenario") is MergeNetwork
    assert network_class("Figure8Scenario") is FigureEightNetwork
    assert network_class("HighwayNetwork") is HighwayNetwork
    assert network_class("ring") is RingNetwork
    table = {name: (cls, params) for name, cls, params in network_table()}
    assert set(table) == {"ring", "figure_eight", "merge", "highway", "template",
                          "traffic_light_grid", "bottleneck", "highway_ramps",
                          "i210_subnetwork", "minicity", "multi_ring"}  # fmt: skip
    assert table["highway"][1]["boundary_cell_length"] == 500
    assert table["merge"][0] == "MergeNetwork"


def test_flow_module_paths_exist() -> None:
    from flowrun.networks.figure_eight import ADDITIONAL_NET_PARAMS as FIG8
    from flowrun.networks.highway import ADDITIONAL_NET_PARAMS as HIGHWAY
    from flowrun.networks.merge import ADDITIONAL_NET_PARAMS as MERGE
    from flowrun.scenarios import Figure8Scenario, HighwayScenario, LoopScenario, MergeScenario

    assert FIG8 == {"radius_ring": 30, "lanes": 1, "speed_limit": 30, "resolution": 40}
    assert MERGE == {"merge_length": 100, "pre_merge_length": 200, "post_merge_length": 100,
                     "merge_lanes": 1, "highway_lanes": 1, "speed_limit": 30}  # fmt: skip
    assert HIGHWAY == {"length": 1000, "lanes": 4, "speed_limit": 30, "num_edges": 1,
                       "use_ghost_edge": False, "ghost_speed_limit": 25,
                       "boundary_cell_length": 500}  # fmt: skip
    assert (Figure8Scenario, MergeScenario, HighwayScenario, LoopScenario) == (
        FigureEightNetwork, MergeNetwork, HighwayNetwork, RingNetwork)  # fmt: skip


# --- template and OSM ----------------------------------------------------------------------


def merge_net(tmp_path: Path) -> Path:
    return build_network(make(MergeNetwork).spec, tmp_path / "built", "merge")


def test_template_reads_edges_and_routes_from_a_net_file(tmp_path: Path) -> None:
    net = merge_net(tmp_path)
    routes = {
        "inflow_highway": ["inflow_highway", "left", "center"],
        "inflow_merge": [[["inflow_merge", "bottom", "center"], 0.25],
                         [["inflow_merge", "bottom"], 0.75]],
    }  # fmt: skip
    spec = make(TemplateNetwork, template=str(net), routes=routes).spec
    assert spec.net_file == str(net)
    assert build_network(spec, tmp_path / "other") == net  # used as is
    assert {e.id: e.length for e in spec.edges}["left"] == pytest.approx(200)
    assert spec.routes["inflow_merge"] == ("inflow_merge", "bottom")
    assert spec.choices("inflow_merge")[0] == (("inflow_merge", "bottom", "center"), 0.25)
    starts = sorted(spec.edge_starts.values())
    assert starts[0] == 0.0 and spec.length == pytest.approx(600)


def test_template_dict_form_keeps_route_and_vtype_files(tmp_path: Path) -> None:
    net = merge_net(tmp_path)
    rou = tmp_path / "x.rou.xml"
    rou.write_text("<routes/>")
    spec = make(TemplateNetwork, template={"net": str(net), "rou": str(rou)}).spec
    assert spec.extra_files == (str(rou),)
    assert spec.routes["left"] == ("left",)  # no routes given: each car drives its edge


def test_template_route_through_unconnected_edges_is_refused(tmp_path: Path) -> None:
    net = merge_net(tmp_path)
    with pytest.raises(ConfigError, match="from 'left' to 'bottom'") as err:
        make(TemplateNetwork, template=str(net), routes={"left": ["left", "bottom"]})
    assert str(net) in str(err.value) and err.value.path == "routes.left"
    with pytest.raises(ConfigError, match="did you mean 'center'"):
        make(TemplateNetwork, template=str(net), routes={"left": ["left", "centre"]})
    with pytest.raises(ConfigError, match=r"sum to 0\.5"):
        make(TemplateNetwork, template=str(net), routes={"left": [[["left"], 0.5]]})


def test_template_missing_or_not_a_net_file_names_the_file(tmp_path: Path) -> None:
    missing = tmp_path / "nope.net.xml"
    with pytest.raises(ConfigError, match=r"nope\.net.xml' not found") as err:
        make(TemplateNetwork, template=str(missing))
    assert err.value.path == "template"
    routes = tmp_path / "routes.xml"
    routes.write_text("<routes/>")
    with pytest.raises(ConfigError, match="root element is <routes>, expected <net>"):
        make(TemplateNetwork, template=str(routes))
    junk = tmp_path / "junk.net.xml"
    junk.write_text("this is not xml")
    with pytest.raises(ConfigError, match=r"junk\.net.xml' is not a SUMO network"):
        make(TemplateNetwork, template=str(junk))
    with pytest.raises(ConfigError, match="needs `template"):
        make(TemplateNetwork)


TINY_OSM = """<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="flowrun-test">
  <bounds minlat="52.5000" minlon="13.4000" maxlat="52.5020" maxlon="13.4040"/>
  <node id="1" lat="52.5000" lon="13.4000" version="1" visible="true"/>
  <node id="2" lat="52.5010" lon="13.4020" version="1" visible="true"/>
  <node id="3" lat="52.5020" lon="13.4040" version="1" visible="true"/>
  <way id="10" version="1" visible="true">
    <nd ref="1"/><nd ref="2"/><nd ref="3"/>
    <tag k="highway" v="primary"/><tag k="oneway" v="yes"/><tag k="lanes" v="2"/>
  </way>
</osm>
"""


def test_osm_file_is_imported_by_netconvert(tmp_path: Path) -> None:
    osm = tmp_path / "tiny.osm"
    osm.write_text(TINY_OSM)
    net = convert_osm(osm, tmp_path / "cache")
    edges, _ = read_built(net)
    assert len(edges) == 1 and len(next(iter(edges.values()))) == 2
    assert convert_osm(osm, tmp_path / "cache") == net  # cached by content


def test_osm_file_netconvert_rejects_gives_one_message_naming_it(tmp_path: Path) -> None:
    bad = tmp_path / "bad.osm"
    bad.write_text("garbage")
    with pytest.raises(ConfigError, match=r"could not import OSM file .*bad\.osm.*Error") as err:
        convert_osm(bad, tmp_path / "cache")
    assert err.value.path == "osm_path"
    assert "\n" not in str(err.value)
    with pytest.raises(ConfigError, match=r"missing\.osm' not found"):
        make(TemplateNetwork, osm=str(tmp_path / "missing.osm"))


def test_list_networks_shows_each_type_with_its_parameters() -> None:
    from typer.testing import CliRunner

    from flowrun.cli.main import app

    result = CliRunner().invoke(app, ["list", "networks"])
    assert result.exit_code == 0, result.output
    lines = {line.split()[0]: line for line in result.stdout.splitlines()}
    assert set(lines) == {"ring", "figure_eight", "merge", "highway", "template",
                          "traffic_light_grid", "bottleneck", "highway_ramps",
                          "i210_subnetwork", "minicity", "multi_ring"}  # fmt: skip
    assert "radius_ring=30" in lines["figure_eight"]
    assert (
        "use_ghost_edge=false" in lines["highway"]
        and "boundary_cell_length=500" in lines["highway"]
    )
    assert "MergeNetwork" in lines["merge"] and "pre_merge_length=200" in lines["merge"]


def test_figure_eight_edge_starts_follow_the_loop_without_gaps_beyond_the_links() -> None:
    from flowrun.networks.figure_eight import LOOP, figure_eight_edge_starts

    r, lanes = 30.0, 1
    starts = figure_eight_edge_starts(r, lanes)
    length = {"bottom": r, "top": r, "right": r, "left": r,
              "upper_ring": 3 * np.pi * r / 2, "lower_ring": 3 * np.pi * r / 2}  # fmt: skip
    for a, b in itertools.pairwise(LOOP):
        # the next edge starts after this one plus a junction link (< 10 m), never before
        assert 0 < starts[b] - (starts[a] + length[a]) < 10, (a, b)
    end = starts["lower_ring"] + length["lower_ring"]
    assert end == pytest.approx(4 * r + 3 * np.pi * r + 2 * (2.9 + 3.3 * lanes) + 4 * 0.28)
