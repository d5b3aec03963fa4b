"""Flow's I-210 sub-network: routes over a user-supplied I-210 template.

The road is the SUMO network of a stretch of the I-210 freeway (Los Angeles) that Flow ships
as ``examples/exp_configs/templates/sumo/i210_with_ghost_cell*.xml``; give its path as
``NetParams(template=...)`` (YAML ``network.template``). This class adds Flow's routes over
its edges: the main highway from ``119257914`` (``ghost0``, the downstream-slowing ghost
cell, first when ``ghost_edge``), and with ``on_ramp`` routes from every main-highway edge
and from the on-ramp (edges ``27414345`` / ``27414342#0``), whose cars take the off-ramp
``173381935`` with Flow's probabilities (9/321, 20/421, 1/2). Positions along the main
highway use Flow's measured edge and junction lengths.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, ClassVar

from flowrun.networks.spec import NetworkSpec
from flowrun.networks.template import TemplateNetwork

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # whether to include vehicles on the on-ramp (its routes)
    "on_ramp": False,
    # whether to include the downstream slow-down edge (ghost0) in the network
    "ghost_edge": False,
}

#: Flow's ``EDGES_DISTRIBUTION``: the edges cars may be placed on
EDGES_DISTRIBUTION = [
    "ghost0", "119257914", "119257908#0", "119257908#1-AddedOnRampEdge", "119257908#1",
    "119257908#1-AddedOffRampEdge", "119257908#2", "119257908#3",
    "27414345", "27414342#0", "27414342#1-AddedOnRampEdge",
    "173381935",
]  # fmt: skip

#: the main highway in driving order with its junctions and their lengths, m (Flow's)
LENGTH_WITH_GHOST_EDGE: list[tuple[str, float]] = [
    ("ghost0", 573.08), (":300944378_0", 0.30), ("119257914", 61.28),
    (":300944379_0", 0.31), ("119257908#0", 696.97), (":300944436_0", 2.87),
    ("119257908#1-AddedOnRampEdge", 97.20), (":119257908#1-AddedOnRampNode_0", 3.24),
    ("119257908#1", 239.68), (":119257908#1-AddedOffRampNode_0", 3.24),
    ("119257908#1-AddedOffRampEdge", 98.50), (":1686591010_1", 5.46),
    ("119257908#2", 576.61), (":1842086610_1", 4.53), ("119257908#3", 17.49),
]  # fmt: skip

MAIN = tuple(e for e, _ in LENGTH_WITH_GHOST_EDGE if not e.startswith(":"))
RAMP_IN = ("27414342#1-AddedOnRampEdge", "27414342#1")
OFF_RAMP = "173381935"
#: on-ramp start edge -> Flow's probability of leaving at the off-ramp
OFF_RAMP_PROBA = {"27414345": 9 / 321, "27414342#0": 20 / 421, RAMP_IN[0]: 0.5}


def i210_routes(on_ramp: bool, ghost_edge: bool) -> dict[str, list[tuple[list[str], float]]]:
    """Flow's ``specify_routes`` of the I-210 sub-network."""
    merge_at = MAIN.index("119257908#1-AddedOnRampEdge")
    exit_at = MAIN.index("119257908#1-AddedOffRampEdge")
    routes = {MAIN[1]: [(list(MAIN[1:]), 1.0)]}
    if ghost_edge:
        routes[MAIN[0]] = [(list(MAIN), 1.0)]
    if on_ramp:
        routes |= {e: [(list(MAIN[i:]), 1.0)] for i, e in enumerate(MAIN) if i > 1}
        for start, p in OFF_RAMP_PROBA.items():
            head = [start] + [e for e in RAMP_IN if e != start]
            routes[start] = [
                ([*head, *MAIN[merge_at:]], 1 - p),
                ([*head, *MAIN[merge_at : exit_at + 1], OFF_RAMP], p),
            ]
        routes[OFF_RAMP] = [([OFF_RAMP], 1.0)]
    return routes


class I210SubNetwork(TemplateNetwork):
    """Flow's ``I210SubNetwork`` on the user's I-210 template (module docstring).

    ``net_params.template``: the I-210 ``.net.xml`` (or Flow's dict ``{net, rou, vtype}``);
    ``net_params.additional_params``: ``on_ramp``, ``ghost_edge`` (see
    :data:`ADDITIONAL_NET_PARAMS`).
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    PARAM_KINDS: ClassVar[dict[str, str]] = {"on_ramp": "flag", "ghost_edge": "flag"}
    network_type: ClassVar[str] = "i210_subnetwork"
    LIST_NOTE: ClassVar[str] = "with template: Flow's i210_with_ghost_cell*.xml"

    @classmethod
    def resolve_params(cls, given: dict[str, Any]) -> dict[str, Any]:
        """Flow's two flags over their defaults; unknown keys are errors."""
        return super(TemplateNetwork, cls).resolve_params(given)

    def specify_routes(self, net_params: Any) -> Mapping[str, Any]:
        """Flow's routes (see :func:`i210_routes`)."""
        return i210_routes(bool(self.params["on_ramp"]), bool(self.params["ghost_edge"]))

    def build_spec(self) -> NetworkSpec:
        """The template's road with Flow's routes and main-highway positions."""
        spec = super().build_spec()
        table = LENGTH_WITH_GHOST_EDGE if self.params["ghost_edge"] else LENGTH_WITH_GHOST_EDGE[2:]
        starts, x = {}, 0.0
        for edge, length in table:
            starts[edge] = x
            x += length
        for e in spec.edges:  # the ramps (and anything else) after the main highway
            if e.id not in starts:
                starts[e.id] = x
                x += e.length
        main = tuple(e for e, _ in table if not e.startswith(":"))
        return dataclasses.replace(spec, edge_starts=starts, main_route=main)
