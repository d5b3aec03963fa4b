"""Flow's ``Network`` attributes (``nodes``, ``edges``, ``routes``, ``edge_starts``, ...) as
read-only views of a flowrun network's spec, in Flow's formats, for Flow code that reads
them (``network.routes[edge]``, ``network.edge_starts``)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from flowrun.networks.template_read import rou_routes


class _view:  # lower case: used as a decorator, like ``property``
    """A read-only computed attribute that an instance may still assign (a user's Flow
    network that sets ``self.edges = ...`` in its ``__init__`` keeps its own value)."""

    def __init__(self, fn: Callable[[Any], Any]) -> None:
        self.fn = fn
        self.__doc__ = fn.__doc__

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        return self if obj is None else self.fn(obj)


class FlowAttributes:
    """Mixin of :class:`~flowrun.networks.base.Network`: Flow's attribute names over
    ``self.spec`` (a :class:`~flowrun.networks.base.NetworkSpec`)."""

    spec: Any

    @_view
    def nodes(self) -> list[dict[str, Any]]:
        """Flow's ``nodes``: ``[{id, x, y, type[, radius]}]``."""
        out = []
        for n in self.spec.nodes:
            node: dict[str, Any] = {"id": n.id, "x": n.x, "y": n.y, "type": n.type}
            if n.radius is not None:
                node["radius"] = n.radius
            out.append(node)
        return out

    @_view
    def edges(self) -> list[dict[str, Any]]:
        """Flow's ``edges``: ``[{id, from, to, length, numLanes, speed, priority[, shape]
        [, spreadType]}]``."""
        out = []
        for e in self.spec.edges:
            edge: dict[str, Any] = {
                "id": e.id, "from": e.from_node, "to": e.to_node, "length": e.length,
                "numLanes": e.lanes, "speed": e.speed, "priority": e.priority,
            }  # fmt: skip
            if e.shape:
                edge["shape"] = list(e.shape)
            if e.spread_type != "right":
                edge["spreadType"] = e.spread_type
            out.append(edge)
        return out

    @_view
    def types(self) -> list[dict[str, Any]]:
        """Flow's ``types``: empty (every edge in :attr:`edges` carries its lanes and speed)."""
        return []

    @_view
    def connections(self) -> list[dict[str, Any]] | None:
        """Flow's ``connections``: ``[{from, to, fromLane, toLane}]``, ``None`` without any."""
        conns = [
            {"from": c.from_edge, "to": c.to_edge, "fromLane": c.from_lane, "toLane": c.to_lane}
            for c in self.spec.connections
        ]
        return conns or None

    @_view
    def routes(self) -> dict[str, Any]:
        """Flow's ``routes`` as its kernel leaves them: ``{start edge: [(edges, prob)]}``;
        with a template dict's ``rou`` file, that file's ``{route or vehicle id: [edges]}``,
        as Flow's network reads them (:func:`~flowrun.networks.template_read.rou_routes`)."""
        template = getattr(getattr(self, "net_params", None), "template", None)
        if isinstance(template, Mapping) and template.get("rou"):
            return rou_routes(template["rou"])
        starts = dict.fromkeys((*self.spec.routes, *self.spec.route_choices))
        return {e: [(list(r), float(p)) for r, p in self.spec.choices(e)] for e in starts}

    @_view
    def edge_starts(self) -> list[tuple[str, float]]:
        """Flow's ``edge_starts``: ``[(edge, position along the network, m)]`` of the edges."""
        return [(e, x) for e, x in self.spec.edge_starts.items() if not e.startswith(":")]

    @_view
    def internal_edge_starts(self) -> list[tuple[str, float]]:
        """Flow's ``internal_edge_starts``: the junction links the network positions itself
        (once SUMO has built the road, ``k.network`` knows every link)."""
        return [(e, x) for e, x in self.spec.edge_starts.items() if e.startswith(":")]

    @_view
    def intersection_edge_starts(self) -> list[tuple[str, float]]:
        """Flow's (deprecated) ``intersection_edge_starts``: always empty, as in Flow."""
        return []
