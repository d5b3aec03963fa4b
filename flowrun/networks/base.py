"""Networks as data: nodes, edges and routes that ``build.py`` turns into a SUMO ``.net.xml``.

A :class:`Network` is Flow's network object (``name, vehicles, net_params, initial_config``):
subclasses describe their road as a :class:`NetworkSpec` and say where vehicles start.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from flowrun.config.params import (
    InitialConfig,
    NetParams,
    TrafficLightParams,
    VehicleParams,
)
from flowrun.errors import ConfigError
from flowrun.networks.flow_attributes import FlowAttributes
from flowrun.suggest import did_you_mean


@dataclass(frozen=True)
class Node:
    """A junction: id and coordinates in metres."""

    id: str
    x: float
    y: float
    type: str = "priority"
    radius: float | None = None


@dataclass(frozen=True)
class Edge:
    """A road from one node to another.

    Attributes:
        id: edge id.
        from_node: start node id.
        to_node: end node id.
        length: length in metres (forced, so positions add up exactly).
        lanes: number of lanes.
        speed: speed limit, m/s.
        shape: polyline (x, y) points, metres.
        priority: SUMO edge priority (decides right of way at priority junctions).
        spread_type: SUMO ``spreadType``: ``right`` (lanes to the right of the edge's line,
            netconvert's default) or ``center`` / ``roadCenter`` (lanes centred on it).
    """

    id: str
    from_node: str
    to_node: str
    length: float
    lanes: int
    speed: float
    shape: tuple[tuple[float, float], ...] = ()
    priority: int = 78
    spread_type: str = "right"


@dataclass(frozen=True)
class Connection:
    """A lane-to-lane connection through a junction (Flow's ``specify_connections`` entries)."""

    from_edge: str
    to_edge: str
    from_lane: int
    to_lane: int


#: One route choice: the edges driven and the probability of taking it.
RouteChoice = tuple[tuple[str, ...], float]


@dataclass(frozen=True)
class TemplateVehicle:
    """A vehicle of a template's route file, added at every reset (Flow's template vehicles).

    Attributes:
        id: vehicle id.
        type: vehicle type id.
        route: the edges it drives.
        depart: departure time as written, s (it departs that long after the reset).
        depart_pos: SUMO ``departPos`` (text, e.g. ``"12.5"`` or ``"base"``).
        depart_speed: SUMO ``departSpeed`` (text, e.g. ``"0"`` or ``"max"``).
    """

    id: str
    type: str
    route: tuple[str, ...]
    depart: float
    depart_pos: str = "base"
    depart_speed: str = "0"


@dataclass(frozen=True)
class NetworkSpec:
    """Everything SUMO needs to build the road, plus flowrun's own coordinates.

    Attributes:
        nodes: junctions.
        edges: roads, in driving order for closed networks.
        routes: start edge -> the edges of its (most likely) route; vehicles starting on edge
            ``e`` use route ``e``.
        edge_starts: edge id -> position of the edge's start along the network, metres.
            Junction-internal edges (ids starting with ``:``) may be listed; the kernel places
            the ones that are not right after the edge that leads into them.
        length: total length of the network along its edges, metres.
        closed: ``True`` for a ring (positions wrap at ``length``).
        extra: network-specific facts (e.g. the ring's radius).
        connections: lane-to-lane connections; empty lets netconvert decide.
        route_choices: start edge -> ``((edges, probability), ...)`` when a start edge has
            several routes (Flow's ``[(route, prob)]`` form); empty otherwise.
        internal_links: build junction-internal lanes (all networks but the ring, whose
            positions must add up exactly around the loop).
        main_route: the edges of the network's main road, in driving order (time-space
            diagrams follow it); empty means the edges in their listed order.
        net_file: an existing ``.net.xml`` to use as is (``NetParams(template=...)``) instead
            of building one from nodes and edges.
        extra_files: further SUMO route files of a template.
        departures: vehicles added at every reset with a departure time (a template's).
    """

    nodes: tuple[Node, ...]
    edges: tuple[Edge, ...]
    routes: dict[str, tuple[str, ...]]
    edge_starts: dict[str, float]
    length: float
    closed: bool = False
    extra: dict[str, Any] = field(default_factory=dict)
    connections: tuple[Connection, ...] = ()
    route_choices: dict[str, tuple[RouteChoice, ...]] = field(default_factory=dict)
    internal_links: bool = False
    main_route: tuple[str, ...] = ()
    net_file: str | None = None
    extra_files: tuple[str, ...] = ()
    departures: tuple[TemplateVehicle, ...] = ()

    def choices(self, start_edge: str) -> tuple[RouteChoice, ...]:
        """The route choices of vehicles starting on ``start_edge`` (one sure route if fixed)."""
        if start_edge in self.route_choices:
            return self.route_choices[start_edge]
        if start_edge in self.routes:
            return ((self.routes[start_edge], 1.0),)
        return ()


@dataclass(frozen=True)
class StartPositions:
    """Where each vehicle enters: parallel lists in ``VehicleParams.ids`` order.

    Attributes:
        edges: edge id of each vehicle.
        lane_pos: position on that edge, metres (front bumper).
        lanes: lane index.
    """

    edges: list[str]
    lane_pos: list[float]
    lanes: list[int]


class Network(FlowAttributes):
    """Base of all networks (Flow's ``Network``/``Scenario``).

    Args:
        name: experiment name.
        vehicles: the vehicles to place.
        net_params: ``additional_params`` of the network type (see ``ADDITIONAL_NET_PARAMS``).
        initial_config: initial placement.
        traffic_lights: traffic lights (unused by the ring).
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = {}
    #: the kind of each parameter (see :func:`flowrun.networks.checks.check_values`),
    #: checked by :meth:`resolve_params`
    PARAM_KINDS: ClassVar[dict[str, str]] = {}
    #: keys Flow's own examples pass to this network although it does not use them
    #: (e.g. a ring's ``resolution`` given to the highway): accepted and left unused, as in
    #: Flow, instead of being refused as unknown
    UNUSED_FLOW_PARAMS: ClassVar[frozenset[str]] = frozenset()
    network_type: ClassVar[str] = ""

    def __init__(
        self,
        name: str,
        vehicles: VehicleParams,
        net_params: NetParams,
        initial_config: InitialConfig | None = None,
        traffic_lights: TrafficLightParams | None = None,
    ) -> None:
        self.name = name
        self.orig_name = name
        self.vehicles = vehicles
        self.net_params = net_params
        self.initial_config = initial_config or InitialConfig()
        self.traffic_lights = traffic_lights or TrafficLightParams()
        self.params = self.resolve_params(net_params.additional_params)
        self.spec = self.build_spec()
        if lights := self.traffic_lights.get_properties():  # Flow: the node becomes a light
            from flowrun.networks.flow_hooks import lights_on_nodes

            self.spec = lights_on_nodes(self.spec, lights)
        if isinstance(net_params.template, Mapping):  # Flow's {net, rou, vtype}
            from flowrun.networks.template_demand import apply_template

            self.vehicles, self.spec = apply_template(net_params.template, vehicles, self.spec)

    @classmethod
    def resolve_params(cls, given: dict[str, Any]) -> dict[str, Any]:
        """``ADDITIONAL_NET_PARAMS`` overlaid with ``given``; unknown keys are errors."""
        params = dict(cls.ADDITIONAL_NET_PARAMS)
        if not params:  # a user's network that declares none takes what it is given (Flow)
            return dict(given)
        for key, value in given.items():
            if key in cls.UNUSED_FLOW_PARAMS and key not in params:
                continue
            if key not in params:
                raise ConfigError(
                    f"unknown parameter of network '{cls.network_type}'"
                    f"{did_you_mean(key, params)}; expected: {', '.join(params)}",
                    path=key,
                )
            params[key] = value
        if cls.PARAM_KINDS:
            from flowrun.networks.checks import check_values

            check_values(params, cls.PARAM_KINDS)
        return params

    def with_params(self, **changes: Any) -> Network:
        """The same network with some ``additional_params`` changed (e.g. a new ring length)."""
        params = dict(self.net_params.additional_params)
        params.update(changes)
        return type(self)(
            self.name,
            self.vehicles,
            NetParams(
                additional_params=params,
                inflows=self.net_params.inflows,
                template=self.net_params.template,
                osm_path=self.net_params.osm_path,
            ),
            self.initial_config,
            self.traffic_lights,
        )

    def build_spec(self) -> NetworkSpec:
        """Describe the road: from Flow's ``specify_*`` methods unless a subclass overrides
        this (as flowrun's own networks do).

        Raises:
            ConfigError: the class implements neither.
        """
        np_ = self.net_params
        if type(self).specify_edges is Network.specify_edges and (
            np_.template is not None or np_.osm_path is not None
        ):  # Flow's way of using a template: only specify_routes is written
            from flowrun.networks.template import TemplateNetwork

            return TemplateNetwork.build_spec(self)  # type: ignore[arg-type]
        if type(self).specify_edges is Network.specify_edges:
            raise ConfigError(
                f"network class {type(self).__name__} describes no road: implement Flow's "
                "specify_nodes / specify_edges / specify_routes (and optionally "
                "specify_types, specify_connections, specify_edge_starts)"
            )
        from flowrun.networks.flow_hooks import spec_from_hooks

        return spec_from_hooks(self)

    def start_positions(self, rng: np.random.Generator) -> StartPositions:
        """Initial position of every vehicle: Flow's ``InitialConfig`` placement over the
        network's edges (subclasses may override)."""
        from flowrun.networks.placement import place_on_network, vehicle_space

        if self.initial_config.spacing == "custom":
            return self.custom_start_positions()
        return place_on_network(self.spec, vehicle_space(self.vehicles), self.initial_config, rng)

    def custom_start_positions(self) -> StartPositions:
        """Flow's ``spacing="custom"``: the network's own ``gen_custom_start_pos``.

        Flow declares it ``gen_custom_start_pos(cls, net_params, initial_config, num_vehicles)``
        (a static method taking the class) and expects ``([(edge, pos), ...], [lane, ...])``.

        Raises:
            ConfigError: the network defines no ``gen_custom_start_pos``.
        """
        cls = type(self)
        raw = inspect.getattr_static(cls, "gen_custom_start_pos", None)
        if raw is None:
            raise ConfigError(
                f"initial.spacing 'custom' asks {cls.__name__}.gen_custom_start_pos for the "
                "positions, but the network defines none; use 'uniform' or 'random'",
                path="spacing",
            )
        n = self.vehicles.num_vehicles
        args = (self.net_params, self.initial_config, n)
        if isinstance(raw, staticmethod):
            fn = raw.__func__
            got = fn(cls, *args) if len(inspect.signature(fn).parameters) == 4 else fn(*args)
        else:
            got = getattr(self, "gen_custom_start_pos")(*args)  # noqa: B009
        positions, lanes = got
        edges = [str(e) for e, _ in positions]
        return StartPositions(edges, [float(x) for _, x in positions], [int(x) for x in lanes])

    # ------------------------------------------------------------------ Flow's hooks
    def specify_nodes(self, net_params: NetParams) -> list[dict[str, Any]]:
        """Flow's hook: ``[{id, x, y[, type, radius]}]``."""
        return []

    def specify_edges(self, net_params: NetParams) -> list[dict[str, Any]]:
        """Flow's hook: ``[{id, from, to, length, numLanes, speed | type[, shape, priority]}]``."""
        return []

    def specify_types(self, net_params: NetParams) -> list[dict[str, Any]]:
        """Flow's hook: ``[{id, numLanes, speed}]``."""
        return []

    def specify_connections(self, net_params: NetParams) -> Any:
        """Flow's hook: ``{node_id: [{from, to, fromLane, toLane}]}`` (or a flat list)."""
        return None

    def specify_routes(self, net_params: NetParams) -> Mapping[str, Any]:
        """Flow's hook: ``{start_edge: [edges]}`` or ``{start_edge: [(edges, prob), ...]}``."""
        return {}

    def specify_edge_starts(self) -> list[tuple[str, float]]:
        """Flow's hook: ``[(edge, start position along the network, m)]``."""
        return []

    def specify_internal_edge_starts(self) -> list[tuple[str, float]]:
        """Flow's hook: ``[(":internal_edge", start, m)]``; unlisted ones are derived."""
        return []

    @property
    def length(self) -> float:
        """Total length along the edges, metres."""
        return self.spec.length
