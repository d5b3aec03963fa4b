"""A network written Flow's way: ``specify_nodes``, ``specify_edges``, ... turned into a spec.

Flow's tutorial on creating networks subclasses ``Network`` and returns plain dicts from
``specify_nodes(net_params)``, ``specify_edges(net_params)``, ``specify_types(net_params)``,
``specify_connections(net_params)``, ``specify_routes(net_params)``,
``specify_edge_starts()`` and ``specify_internal_edge_starts()``. This module reads those
dicts (Flow's keys: ``numLanes``, ``speed``, ``from``, ``to``, ``fromLane``, ...) into a
:class:`NetworkSpec`, checking what netconvert would otherwise reject obscurely.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import replace
from typing import Any

from flowrun.errors import ConfigError
from flowrun.networks.route_forms import parse_routes
from flowrun.networks.spec import Connection, Edge, NetworkSpec, Node
from flowrun.suggest import did_you_mean

#: SUMO's edge ``spreadType`` values (where an edge's lanes lie relative to its line)
SPREAD_TYPES = ("right", "center", "roadCenter")


def spec_from_hooks(network: Any) -> NetworkSpec:
    """The spec of a network whose class implements Flow's ``specify_*`` methods."""
    net_params = network.net_params
    name = type(network).__name__
    nodes = tuple(_node(n, name) for n in network.specify_nodes(net_params) or ())
    types = {t["id"]: t for t in network.specify_types(net_params) or ()}
    node_xy = {n.id: (n.x, n.y) for n in nodes}
    edges = tuple(_edge(e, types, node_xy, name) for e in network.specify_edges(net_params) or ())
    edge_ids = {e.id for e in edges}
    connections = _connections(network.specify_connections(net_params), edge_ids, name)
    routes, choices = parse_routes(
        _routes_or_default(network, edges), edge_ids, None, f"{name}.specify_routes"
    )
    starts = dict(network.specify_edge_starts() or ())
    if not starts:  # Flow's default: edges laid end to end in the order given
        at = 0.0
        for e in edges:
            starts[e.id] = at
            at += e.length
    starts.update(dict(network.specify_internal_edge_starts() or ()))
    return NetworkSpec(
        nodes,
        edges,
        routes,
        starts,
        float(sum(e.length for e in edges)),
        connections=connections,
        route_choices=choices,
        internal_links=True,
    )


def _routes_or_default(network: Any, edges: Sequence[Edge]) -> Mapping[str, Any]:
    """``specify_routes``'s answer; Flow's default when it gives none: one route per edge,
    that edge alone (``{edge: [edge]}``)."""
    given = network.specify_routes(network.net_params)
    return given if given else {e.id: [e.id] for e in edges}


def overlay_hooks(network: Any, spec: NetworkSpec, base: type) -> NetworkSpec:
    """``spec`` (a built-in network's road) with the answers of the Flow hooks that a user's
    subclass of that network overrides, as in Flow, where a subclass of ``RingNetwork``
    may redefine only ``specify_edges`` or ``specify_routes``.

    Args:
        network: the network object.
        spec: the built-in network's spec.
        base: the built-in network class whose own hooks do not count as overridden.
    """
    cls = type(network)

    def overridden(name: str) -> bool:
        return getattr(cls, name) is not getattr(base, name)

    if not (overridden("specify_edges") or overridden("specify_routes")):
        return spec
    name = cls.__name__
    edges = spec.edges
    if overridden("specify_edges"):
        net_params = network.net_params
        types = {t["id"]: t for t in network.specify_types(net_params) or ()}
        node_xy = {n.id: (n.x, n.y) for n in spec.nodes}
        edges = tuple(
            _edge(e, types, node_xy, name) for e in network.specify_edges(net_params) or ()
        )
    routes, choices = parse_routes(
        _routes_or_default(network, edges) if overridden("specify_routes") else spec.routes,
        {e.id for e in edges}, None, f"{name}.specify_routes",
    )  # fmt: skip
    return replace(
        spec, edges=edges, routes=routes, route_choices=choices,
        length=float(sum(e.length for e in edges)),
    )  # fmt: skip


def _node(n: Mapping[str, Any], owner: str) -> Node:
    try:
        return Node(
            str(n["id"]),
            float(n["x"]),
            float(n["y"]),
            str(n.get("type", "priority")),
            None if n.get("radius") is None else float(n["radius"]),
        )
    except KeyError as err:
        missing = err.args[0]
        raise ConfigError(f"{owner}.specify_nodes: a node lacks {missing!r}: {dict(n)}") from None


def _edge(
    e: Mapping[str, Any],
    types: Mapping[str, Mapping[str, Any]],
    node_xy: Mapping[str, tuple[float, float]],
    owner: str,
) -> Edge:
    where = f"{owner}.specify_edges"
    for key in ("id", "from", "to"):
        if key not in e:
            raise ConfigError(f"{where}: an edge lacks {key!r}: {dict(e)}")
    for key in ("from", "to"):
        if e[key] not in node_xy:
            raise ConfigError(
                f"{where}: edge {e['id']!r} {key} node {e[key]!r} is not among the nodes"
                f"{did_you_mean(str(e[key]), node_xy)}"
            )
    kind = types.get(e["type"], {}) if "type" in e else {}
    if "type" in e and e["type"] not in types:
        raise ConfigError(f"{where}: edge {e['id']!r} has unknown type {e['type']!r}")
    lanes = e.get("numLanes", kind.get("numLanes", 1))
    speed = e.get("speed", kind.get("speed", 30.0))
    shape = tuple((float(x), float(y)) for x, y in e.get("shape") or ())
    spread = str(e.get("spreadType", kind.get("spreadType", "right")))
    if spread not in SPREAD_TYPES:
        raise ConfigError(
            f"{where}: edge {e['id']!r} has spreadType {spread!r}"
            f"{did_you_mean(spread, SPREAD_TYPES)}; SUMO's are {', '.join(SPREAD_TYPES)}"
        )
    length = e.get("length")
    if length is None:  # as netconvert measures it: along the shape, node to node
        points = [node_xy[e["from"]], *shape, node_xy[e["to"]]] if not shape else list(shape)
        length = sum(math.dist(a, b) for a, b in itertools.pairwise(points))
    return Edge(
        str(e["id"]),
        str(e["from"]),
        str(e["to"]),
        float(length),
        int(lanes),
        float(speed),
        shape,
        int(e.get("priority", 78)),
        spread,
    )


def _connections(given: Any, edges: set[str], owner: str) -> tuple[Connection, ...]:
    if not given:
        return ()
    items: Sequence[Mapping[str, Any]]
    if isinstance(given, Mapping):
        items = [c for conns in given.values() for c in conns]
    else:
        items = list(given)
    out = []
    for c in items:
        for key in ("from", "to"):
            if c.get(key) not in edges:
                raise ConfigError(
                    f"{owner}.specify_connections: {key} edge {c.get(key)!r} is not an edge"
                    f"{did_you_mean(str(c.get(key)), edges)}"
                )
        out.append(
            Connection(
                str(c["from"]), str(c["to"]), int(c.get("fromLane", 0)), int(c.get("toLane", 0))
            )
        )
    return tuple(out)


def lights_on_nodes(spec: NetworkSpec, light_ids: Iterable[str]) -> NetworkSpec:
    """``spec`` with every node a traffic light was added on made a ``traffic_light``
    junction, as Flow's network generation does (``TrafficLightParams.add("top")`` on a ring
    puts a light at its ``top`` node). Ids that name no node are left for the light check to
    report; a template's own file is used as is.
    """
    wanted = set(light_ids)
    if spec.net_file is not None or not wanted & {n.id for n in spec.nodes}:
        return spec
    nodes = tuple(
        replace(n, type="traffic_light") if n.id in wanted and n.type != "traffic_light" else n
        for n in spec.nodes
    )
    return replace(spec, nodes=nodes)
