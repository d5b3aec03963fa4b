"""Flow's merge: a highway with one on-ramp joining it at 45 degrees.

Highway: ``inflow_highway`` (100 m) -> ``left`` (``pre_merge_length``) -> ``center``
(``post_merge_length``), along the x axis from x = -100 m. Ramp: ``inflow_merge`` (100 m) ->
``bottom`` (``merge_length``), meeting the highway at node ``center`` (x =
``pre_merge_length``) from the lower left at 45 degrees. Vehicles come from inflows on
``inflow_highway`` and ``inflow_merge`` (Flow's benchmarks start with no vehicles).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

from flowrun.networks.base import Network
from flowrun.networks.spec import Edge, NetworkSpec, Node

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # length of the ramp edge `bottom` that joins the highway, m
    "merge_length": 100,
    # length of the highway edge `left` before the merge, m
    "pre_merge_length": 200,
    # length of the highway edge `center` after the merge, m
    "post_merge_length": 100,
    # number of lanes of the ramp
    "merge_lanes": 1,
    # number of lanes of the highway
    "highway_lanes": 1,
    # speed limit of all edges, m/s
    "speed_limit": 30,
}

KINDS = {"merge_length": "positive", "pre_merge_length": "positive",
         "post_merge_length": "positive", "merge_lanes": "count", "highway_lanes": "count",
         "speed_limit": "positive"}  # fmt: skip

INFLOW_EDGE_LEN = 100.0  # length of `inflow_highway` and `inflow_merge`, m (Flow's constant)
MAIN_ROUTE = ("inflow_highway", "left", "center")


def merge_edge_starts(pre_merge: float, post_merge: float, merge_lanes: int) -> dict[str, float]:
    """Flow's positions (m) of the edges along its notional line, internal links included.

    SUMO's id of the ``left -> center`` link is ``:center_<merge_lanes>`` (the ramp's links
    are numbered first); Flow calls it ``:center``. Flow's numbers assume a 22.5 m link
    there; SUMO 1.28 builds it 24.5 m long (the ramp's link 23.3 m), so positions on it run
    2 m past ``center``'s start.
    """
    inflow = INFLOW_EDGE_LEN
    return {
        "inflow_highway": 0.0,
        "left": inflow + 0.1,
        "center": inflow + pre_merge + 22.6,
        "inflow_merge": inflow + pre_merge + post_merge + 22.6,
        "bottom": 2 * inflow + pre_merge + post_merge + 22.7,
        ":left_0": inflow,
        f":center_{merge_lanes}": inflow + pre_merge + 0.1,
        ":bottom_0": 2 * inflow + pre_merge + post_merge + 22.6,
    }


def merge_spec(
    merge: float,
    pre_merge: float,
    post_merge: float,
    merge_lanes: int,
    highway_lanes: int,
    speed_limit: float,
) -> NetworkSpec:
    """Nodes, edges and routes of Flow's merge (see the module docstring)."""
    c, s = math.cos(math.pi / 4), math.sin(math.pi / 4)
    ramp = merge + INFLOW_EDGE_LEN
    nodes = (
        Node("inflow_highway", -INFLOW_EDGE_LEN, 0.0),
        Node("left", 0.0, 0.0),
        Node("center", pre_merge, 0.0, radius=10.0),
        Node("right", pre_merge + post_merge, 0.0),
        Node("inflow_merge", pre_merge - ramp * c, -ramp * s),
        Node("bottom", pre_merge - merge * c, -merge * s),
    )
    hw, mg, v = highway_lanes, merge_lanes, speed_limit
    edges = (
        Edge("inflow_highway", "inflow_highway", "left", INFLOW_EDGE_LEN, hw, v),
        Edge("left", "left", "center", pre_merge, hw, v),
        Edge("center", "center", "right", post_merge, hw, v),
        Edge("inflow_merge", "inflow_merge", "bottom", INFLOW_EDGE_LEN, mg, v),
        Edge("bottom", "bottom", "center", merge, mg, v),
    )
    routes = {
        "inflow_highway": MAIN_ROUTE,
        "left": ("left", "center"),
        "center": ("center",),
        "inflow_merge": ("inflow_merge", "bottom", "center"),
        "bottom": ("bottom", "center"),
    }
    return NetworkSpec(
        nodes,
        edges,
        routes,
        merge_edge_starts(pre_merge, post_merge, merge_lanes),
        2 * INFLOW_EDGE_LEN + merge + pre_merge + post_merge,
        closed=False,
        internal_links=True,
        main_route=MAIN_ROUTE,
    )


class MergeNetwork(Network):
    """Flow's merge (``MergeNetwork``, formerly ``MergeScenario``).

    ``net_params.additional_params``: ``merge_length``, ``pre_merge_length``,
    ``post_merge_length`` (m), ``merge_lanes``, ``highway_lanes``, ``speed_limit`` (m/s).
    See :data:`ADDITIONAL_NET_PARAMS`.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    PARAM_KINDS: ClassVar[dict[str, str]] = KINDS
    network_type: ClassVar[str] = "merge"

    def build_spec(self) -> NetworkSpec:
        """The merge's nodes, edges and routes."""
        p = self.params
        return merge_spec(
            float(p["merge_length"]), float(p["pre_merge_length"]),
            float(p["post_merge_length"]), int(p["merge_lanes"]), int(p["highway_lanes"]),
            float(p["speed_limit"]),
        )  # fmt: skip


#: Flow's older name of the merge.
MergeScenario = MergeNetwork
