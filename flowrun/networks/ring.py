"""The ring road of Sugiyama et al. (2008): one closed loop, any number of lanes.

The circle is cut into edges (4 on short rings, named as in Flow; more on long rings, since
SUMO's step cost grows with vehicles per lane). Edge lengths are forced to ``length / n`` so
that ring positions add up exactly: position = edge start + lane position.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, ClassVar

import numpy as np

from flowrun.config.params import InitialConfig, VehicleParams
from flowrun.errors import ConfigError
from flowrun.networks.base import Network
from flowrun.networks.flow_hooks import overlay_hooks
from flowrun.networks.placement import SPACINGS, place_on_closed_road
from flowrun.networks.spec import Edge, NetworkSpec, Node, StartPositions
from flowrun.suggest import did_you_mean

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # length of the ring road, m
    "length": 230,
    # number of lanes
    "lanes": 1,
    # speed limit of all edges, m/s
    "speed_limit": 30,
    # number of points in each edge's shape (smoothness of the curve)
    "resolution": 40,
}

FLOW_EDGE_NAMES = ("bottom", "right", "top", "left")
METRES_PER_EDGE = 2300.0  # long rings get one edge per ~575 m (4 edges per 2.3 km)


def ring_edge_count(length: float) -> int:
    """Number of edges a ring of ``length`` metres is cut into (a multiple of 4)."""
    return 4 * max(1, math.ceil(length / METRES_PER_EDGE))


def ring_edge_names(n: int) -> tuple[str, ...]:
    """Flow's names for 4 edges, ``ring_<i>`` otherwise."""
    return FLOW_EDGE_NAMES if n == 4 else tuple(f"ring_{i}" for i in range(n))


def ring_spec(length: float, lanes: int, speed_limit: float, resolution: int) -> NetworkSpec:
    """Nodes, edges and routes of a ring of ``length`` metres centred on the origin.

    Edge ``i`` spans the angles ``[-pi/2 + 2*pi*i/n, -pi/2 + 2*pi*(i+1)/n]`` (counter-clockwise
    from the bottom). The route of each edge runs once around the ring starting on it.
    """
    n = ring_edge_count(length)
    names = ring_edge_names(n)
    radius = length / (2 * math.pi)
    step = 2 * math.pi / n
    nodes = tuple(
        Node(
            names[i],
            radius * math.cos(-math.pi / 2 + i * step),
            radius * math.sin(-math.pi / 2 + i * step),
        )
        for i in range(n)
    )
    points = max(2, int(resolution))
    edges = []
    for i in range(n):
        a0 = -math.pi / 2 + i * step
        shape = tuple(
            (
                radius * math.cos(a0 + k * step / (points - 1)),
                radius * math.sin(a0 + k * step / (points - 1)),
            )
            for k in range(points)
        )
        edges.append(
            Edge(
                names[i],
                names[i],
                names[(i + 1) % n],
                length / n,
                int(lanes),
                float(speed_limit),
                shape,
            )
        )
    routes = {names[i]: tuple(names[(i + k) % n] for k in range(n)) for i in range(n)}
    starts = {names[i]: i * length / n for i in range(n)}
    return NetworkSpec(
        nodes, tuple(edges), routes, starts, float(length), closed=True, extra={"radius": radius}
    )


class RingNetwork(Network):
    """Flow's ring road (``RingNetwork``, formerly ``LoopScenario``).

    ``net_params.additional_params``: ``length`` (m), ``lanes``, ``speed_limit`` (m/s),
    ``resolution`` (shape points per edge). See :data:`ADDITIONAL_NET_PARAMS`.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    network_type: ClassVar[str] = "ring"

    @classmethod
    def resolve_params(cls, given: dict[str, Any]) -> dict[str, Any]:
        """Merge with defaults and check each value."""
        params = super().resolve_params(given)
        check_ring_params(params)
        return params

    def build_spec(self) -> NetworkSpec:
        """The ring's nodes, edges and routes (a subclass's own ``specify_edges`` /
        ``specify_routes`` replace the ring's, as in Flow)."""
        p = self.params
        spec = ring_spec(
            float(p["length"]), int(p["lanes"]), float(p["speed_limit"]), int(p["resolution"])
        )
        return overlay_hooks(self, spec, RingNetwork)

    def start_positions(self, rng: np.random.Generator) -> StartPositions:
        """Flow's initial placement on the ring (see :func:`place_on_closed_road`).

        ``spacing: custom`` asks the network's ``gen_custom_start_pos``; an
        ``edges_distribution`` other than ``all`` places cars on those edges only (Flow's
        placement over open networks); a negative ``bunching`` counts as 0, as in Flow.
        """
        initial = self.initial_config
        own_edges = type(self).specify_edges is not RingNetwork.specify_edges
        if initial.spacing == "custom" or initial.edges_distribution != "all" or own_edges:
            return super().start_positions(rng)
        if initial.spacing not in SPACINGS:
            raise ConfigError(
                f"unknown spacing {initial.spacing!r}{did_you_mean(str(initial.spacing), SPACINGS)}"
                "; use 'uniform', 'random' or 'custom'",
                path="spacing",
            )
        if initial.bunching < 0:
            initial = replace(initial, bunching=0.0)
        lengths = [
            g.car_following_params.length + g.car_following_params.min_gap  # + SUMO's minGap
            for g in self.vehicles.groups
            for _ in range(g.num_vehicles)
        ]
        positions, lanes = place_on_closed_road(
            self.spec.length, int(self.params["lanes"]), lengths, initial, rng
        )
        n_edges = len(self.spec.edges)
        edge_len = self.spec.length / n_edges
        edges, lane_pos = [], []
        for x in positions:
            idx = min(int(x // edge_len), n_edges - 1)
            edges.append(self.spec.edges[idx].id)
            lane_pos.append(float(x - idx * edge_len))
        return StartPositions(edges, lane_pos, lanes)


#: Flow < 0.5 name of the ring (``flow.scenarios.loop.LoopScenario``).
LoopScenario = RingNetwork


def check_ring_params(params: dict[str, Any]) -> None:
    """Raise :class:`ConfigError` for a ring that cannot exist."""
    for key in ("length", "speed_limit"):
        value = params[key]
        if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
            raise ConfigError(f"expected a number > 0, got {value!r}", path=key)
    for key in ("lanes", "resolution"):
        value = params[key]
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ConfigError(f"expected an integer >= 1, got {value!r}", path=key)


def check_ring_fits(
    params: dict[str, Any], vehicles: VehicleParams, initial: InitialConfig
) -> None:
    """Raise :class:`ConfigError` when the vehicles cannot be placed on the ring."""
    length = float(params["length"])
    lanes = int(params["lanes"])
    usable_lanes = int(min(lanes, initial.lanes_distribution))
    available = length - initial.bunching
    if available <= 0:
        raise ConfigError(
            f"initial.bunching ({initial.bunching} m) leaves no room on a {length} m ring; "
            "use a bunching smaller than the ring length",
            path="length",
        )
    per_lane = math.ceil(vehicles.num_vehicles / max(usable_lanes, 1))
    needed = 0.0
    for g in vehicles.groups:
        needed = max(needed, g.car_following_params.length + g.car_following_params.min_gap)
    needed = needed * per_lane
    if vehicles.num_vehicles and needed > available:
        raise ConfigError(
            f"{vehicles.num_vehicles} vehicles need at least {needed:.1f} m per lane "
            f"(length + min_gap each, {per_lane} per lane) but the ring offers "
            f"{available:.1f} m (length {length} - bunching {initial.bunching}); "
            "use fewer vehicles, more lanes or a longer ring",
            path="length",
        )
