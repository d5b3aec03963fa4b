"""Flow's highway with on- and off-ramps: a straight highway cut at every ramp.

Nodes ``highway_0`` .. ``highway_n`` lie on the x axis at 0, every ramp position (sorted)
and ``highway_length`` (radius 10 m); edge ``highway_i`` joins ``highway_i`` to
``highway_{i+1}``. On-ramp ``j`` (edge ``on_ramp_j``, ``on_ramps_length`` long) comes in at
``on_ramps_pos[j]`` from the lower left (``angle_on_ramps``); off-ramp ``j`` leaves at
``off_ramps_pos[j]`` to the lower right (``angle_off_ramps``). Lanes and speed limits per
kind of road as Flow's ``highway_*``, ``on_ramps_*``, ``off_ramps_*``. Where an on-ramp
joins, the node is a SUMO *zipper* junction (ramp and rightmost highway lane take turns):
at Flow's priority junction ramp cars either wait forever for a gap in dense traffic or,
ignoring the right of way as Flow's example does, drive into the highway's cars.

Routes are Flow's: a car drives down the highway and, at each off-ramp, leaves with
probability ``next_off_ramp_proba`` (so a route's probability is the product of its
choices); cars start on ``highway_0`` or an on-ramp (flowrun adds the same choices for the
other highway edges, so cars may be placed anywhere at the start).

Positions along the network: highway edges start where the one before ends plus the link
through the junction between (:func:`through_link`), so positions run on as the cars drive;
the ramps follow the highway's end.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

from flowrun.errors import ConfigError
from flowrun.networks.base import Network
from flowrun.networks.checks import check_values
from flowrun.networks.spec import Edge, NetworkSpec, Node, RouteChoice

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # lengths of the highway, of each on-ramp and of each off-ramp, m
    "highway_length": 300,
    "on_ramps_length": 100,
    "off_ramps_length": 100,
    # lanes of the highway, of each on-ramp and of each off-ramp
    "highway_lanes": 1,
    "on_ramps_lanes": 1,
    "off_ramps_lanes": 1,
    # speed limits of the highway, on-ramps and off-ramps, m/s
    "highway_speed": 10,
    "on_ramps_speed": 10,
    "off_ramps_speed": 10,
    # positions of the on-ramps and off-ramps along the highway, m
    "on_ramps_pos": [],
    "off_ramps_pos": [],
    # probability that a car leaves the highway at the next off-ramp
    "next_off_ramp_proba": 0.2,
    # angles of the ramps, rad
    "angle_on_ramps": -3 * math.pi / 4,
    "angle_off_ramps": -math.pi / 4,
}

KINDS = {"highway_length": "positive", "on_ramps_length": "positive",
         "off_ramps_length": "positive", "highway_lanes": "count", "on_ramps_lanes": "count",
         "off_ramps_lanes": "count", "highway_speed": "positive", "on_ramps_speed": "positive",
         "off_ramps_speed": "positive"}  # fmt: skip

#: Flow's junction radius of the highway nodes, m
RADIUS = 10.0
#: SUMO's default lane width, m
LANE_WIDTH = 3.2


def through_link(ramp_lanes: int, angle: float) -> float:
    """Length of the highway's link through a node where a ramp of ``ramp_lanes`` lanes
    meets it at ``angle`` (rad), m: the junction's two radii plus the ramp's width along the
    road (how netconvert 1.28 shapes it; checked against the built network in the tests)."""
    return 2 * RADIUS + LANE_WIDTH * ramp_lanes / max(abs(math.sin(angle)), 1e-3)


def check_ramps(p: dict[str, Any]) -> tuple[list[float], list[float]]:
    """The on- and off-ramp positions, checked as Flow does.

    Raises:
        ConfigError: a position is not strictly inside the highway, or two are equal, or
            the probability is not in [0, 1].
    """
    length = float(p["highway_length"])
    out = []
    for key in ("on_ramps_pos", "off_ramps_pos"):
        raw = p[key]
        if not isinstance(raw, list | tuple) or not all(
            isinstance(x, int | float) and not isinstance(x, bool) for x in raw
        ):
            raise ConfigError(f"expected a list of positions in m, got {raw!r}", path=key)
        if any(not 0 < x < length for x in raw):
            raise ConfigError(
                f"every ramp must lie strictly inside the highway (0, {length:g}) m, "
                f"got {list(raw)}",
                path=key,
            )
        out.append([float(x) for x in raw])
    on, off = out
    if len(set(on + off)) != len(on) + len(off):
        raise ConfigError(f"two ramps share a position: {sorted(on + off)}", path="off_ramps_pos")
    proba = p["next_off_ramp_proba"]
    if isinstance(proba, bool) or not isinstance(proba, int | float) or not 0 <= proba <= 1:
        raise ConfigError(f"expected a probability in [0, 1], got {proba!r}",
                          path="next_off_ramp_proba")  # fmt: skip
    return on, off


def ramp_routes(
    n_highway: int, ramp_at: dict[int, str], p: float
) -> dict[str, tuple[RouteChoice, ...]]:
    """Route choices by start edge (Flow's ``specify_routes``).

    Args:
        n_highway: number of highway edges (``highway_0`` .. ``highway_{n-1}``).
        ramp_at: highway node index -> the ramp edge there (``on_ramp_j`` ends at it,
            ``off_ramp_j`` starts at it).
        p: probability of leaving at each off-ramp.
    """

    def onward(node: int) -> list[RouteChoice]:
        """Choices of a car arriving at highway node ``node`` (edges from there on)."""
        if node >= n_highway:
            return [((), 1.0)]
        ahead = [((f"highway_{node}", *r), q) for r, q in onward(node + 1)]
        ramp = ramp_at.get(node, "")
        if ramp.startswith("off"):  # Flow's order: staying on first, leaving here last
            return [(r, (1 - p) * q) for r, q in ahead] + [((ramp,), p)]
        return ahead

    choices: dict[str, tuple[RouteChoice, ...]] = {}
    for i in range(n_highway):
        start = f"highway_{i}"
        choices[start] = tuple(((start, *r), q) for r, q in onward(i + 1) if q > 0)
    for node, ramp in ramp_at.items():
        if ramp.startswith("on"):
            choices[ramp] = tuple(((ramp, *r), q) for r, q in onward(node) if q > 0)
        else:
            choices[ramp] = (((ramp,), 1.0),)
    return choices


def highway_ramps_spec(p: dict[str, Any]) -> NetworkSpec:
    """Nodes, edges and route choices of the highway with ramps (module docstring)."""
    on, off = check_ramps(p)
    length = float(p["highway_length"])
    xs = sorted({0.0, *on, *off, length})
    index = {x: i for i, x in enumerate(xs)}
    merges = {index[x] for x in on}
    nodes = [Node(f"highway_{i}", x, 0.0, "zipper" if i in merges else "priority", RADIUS)
             for i, x in enumerate(xs)]  # fmt: skip
    hw_lanes, hw_speed = int(p["highway_lanes"]), float(p["highway_speed"])
    edges = [Edge(f"highway_{i}", f"highway_{i}", f"highway_{i + 1}", xs[i + 1] - xs[i],
                  hw_lanes, hw_speed) for i in range(len(xs) - 1)]  # fmt: skip
    ramp_at: dict[int, str] = {}
    for kind, positions in (("on", on), ("off", off)):
        ramp_len, angle = float(p[f"{kind}_ramps_length"]), float(p[f"angle_{kind}_ramps"])
        lanes, speed = int(p[f"{kind}_ramps_lanes"]), float(p[f"{kind}_ramps_speed"])
        for j, x in enumerate(positions):
            rid = f"{kind}_ramp_{j}"
            nodes.append(Node(rid, x + ramp_len * math.cos(angle), ramp_len * math.sin(angle)))
            ends = (rid, f"highway_{index[x]}") if kind == "on" else (f"highway_{index[x]}", rid)
            edges.append(Edge(rid, *ends, ramp_len, lanes, speed))
            ramp_at[index[x]] = rid
    choices = ramp_routes(len(xs) - 1, ramp_at, float(p["next_off_ramp_proba"]))
    link = {index[x]: through_link(int(p[f"{kind}_ramps_lanes"]), float(p[f"angle_{kind}_ramps"]))
            for kind, positions in (("on", on), ("off", off)) for x in positions}  # fmt: skip
    starts, end = {}, 0.0
    for i, e in enumerate(edges[: len(xs) - 1]):
        end += link.get(i, 0.0)
        starts[e.id] = end
        end += e.length
    for e in edges[len(xs) - 1 :]:  # the ramps after the highway's end
        starts[e.id] = end + 2 * RADIUS
        end = starts[e.id] + e.length
    main = tuple(f"highway_{i}" for i in range(len(xs) - 1))
    return NetworkSpec(
        tuple(nodes),
        tuple(edges),
        {e: max(c, key=lambda rc: rc[1])[0] for e, c in choices.items()},
        starts,
        sum(e.length for e in edges),
        closed=False,
        route_choices={e: c for e, c in choices.items() if len(c) > 1},
        internal_links=True,
        main_route=main,
    )


class HighwayRampsNetwork(Network):
    """Flow's ``HighwayRampsNetwork``: a highway with on- and off-ramps.

    ``net_params.additional_params``: ``highway_length``, ``on_ramps_length``,
    ``off_ramps_length`` (m); ``highway_lanes``, ``on_ramps_lanes``, ``off_ramps_lanes``;
    ``highway_speed``, ``on_ramps_speed``, ``off_ramps_speed`` (m/s); ``on_ramps_pos``,
    ``off_ramps_pos`` (m along the highway); ``next_off_ramp_proba``; ``angle_on_ramps``,
    ``angle_off_ramps`` (rad). See :data:`ADDITIONAL_NET_PARAMS` and the module docstring.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    network_type: ClassVar[str] = "highway_ramps"

    @classmethod
    def resolve_params(cls, given: dict[str, Any]) -> dict[str, Any]:
        """Defaults overlaid with ``given``, each value checked."""
        params = super().resolve_params(given)
        check_values(params, KINDS)
        check_ramps(params)
        return params

    def build_spec(self) -> NetworkSpec:
        """The highway's nodes, edges and route choices."""
        return highway_ramps_spec(self.params)


#: Flow's older name.
HighwayRampsScenario = HighwayRampsNetwork
