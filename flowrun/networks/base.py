"""Networks as data: nodes, edges and routes that ``build.py`` turns into a SUMO ``.net.xml``.

A :class:`Network` is Flow's network object (``name, vehicles, net_params, initial_config``):
subclasses describe their road as a :class:`NetworkSpec` and say where vehicles start.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from flowrun.config.params import (
    InitialConfig,
    NetParams,
    TrafficLightParams,
    VehicleParams,
)
from flowrun.errors import ConfigError
from flowrun.networks.checks import check_values
from flowrun.networks.flow_attributes import FlowAttributes
from flowrun.networks.flow_hooks import lights_on_nodes, spec_from_hooks
from flowrun.networks.placement import place_on_network, vehicle_space
from flowrun.networks.spec import (
    Connection,
    Edge,
    NetworkSpec,
    Node,
    RouteChoice,
    StartPositions,
    TemplateVehicle,
)
from flowrun.networks.template_demand import apply_template
from flowrun.networks.template_read import template_spec
from flowrun.suggest import did_you_mean

__all__ = [  # the road's data types are defined in spec.py and importable from here too
    "Connection",
    "Edge",
    "Network",
    "NetworkSpec",
    "Node",
    "RouteChoice",
    "StartPositions",
    "TemplateVehicle",
]


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
            self.spec = lights_on_nodes(self.spec, lights)
        if isinstance(net_params.template, Mapping):  # Flow's {net, rou, vtype}
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
            return template_spec(np_, self.specify_routes(np_))
        if type(self).specify_edges is Network.specify_edges:
            raise ConfigError(
                f"network class {type(self).__name__} describes no road: implement Flow's "
                "specify_nodes / specify_edges / specify_routes (and optionally "
                "specify_types, specify_connections, specify_edge_starts)"
            )
        return spec_from_hooks(self)

    def start_positions(self, rng: np.random.Generator) -> StartPositions:
        """Initial position of every vehicle: Flow's ``InitialConfig`` placement over the
        network's edges (subclasses may override)."""
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
