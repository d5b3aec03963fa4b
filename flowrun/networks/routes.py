"""The ``.rou.xml`` of an episode: vehicle types, routes and inflows."""

from __future__ import annotations

from typing import Any
from xml.sax.saxutils import quoteattr

from flowrun.config.params import VehicleParams
from flowrun.config.vtype import vtype_attributes
from flowrun.errors import ConfigError
from flowrun.networks.spec import NetworkSpec
from flowrun.suggest import did_you_mean


def routes_xml(spec: NetworkSpec, vehicles: VehicleParams, net_inflows: Any = None) -> str:
    """The ``.rou.xml`` text: one vehicle type per group, the routes of every start edge
    (and of each route choice), and a ``<flow>`` per inflow (``NetParams.inflows``)."""
    rows = ["<routes>"]
    for g in vehicles.groups:
        attrs = {"id": g.veh_id, **vtype_attributes(g.car_following_params, g.lane_change_params)}
        if g.color:
            attrs["color"] = g.color
        text = " ".join(f"{k}={quoteattr(v)}" for k, v in attrs.items())
        rows.append(f"    <vType {text}/>")
    starts = list(spec.routes) + [e for e in spec.route_choices if e not in spec.routes]
    for start in starts:
        choices = spec.choices(start)
        rows.append(_route(route_name(start), choices[0][0] if start not in spec.routes
                           else spec.routes[start]))  # fmt: skip
        if len(choices) > 1:
            rows += [_route(route_name(start, i), edges) for i, (edges, _) in enumerate(choices)]
    inflows = vehicles_inflows(net_inflows)
    for edge in dict.fromkeys(f.edge for f in inflows):
        if not spec.choices(edge):  # an inflow edge no route starts on: drive just that edge
            rows.append(_route(route_name(edge), (edge,)))
    rows += [flow for i, inflow in enumerate(inflows) for flow in flows_xml(spec, inflow, i)]
    rows.append("</routes>")
    return "\n".join(rows) + "\n"


def vehicles_inflows(inflows: Any) -> list[Any]:
    """The inflow entries of an ``InFlows`` (or ``None``)."""
    return [] if inflows is None else list(inflows.get())


def _route(route_id: str, edges: tuple[str, ...]) -> str:
    return f"    <route id={quoteattr(route_id)} edges={quoteattr(' '.join(edges))}/>"


def route_name(start_edge: str, choice: int | None = None) -> str:
    """SUMO id of the route that starts on ``start_edge`` (or of one of its choices)."""
    return f"route_{start_edge}" if choice is None else f"route_{start_edge}_{choice}"


def named_routes(spec: NetworkSpec) -> dict[str, tuple[str, int | None]]:
    """Each route by the names an inflow's ``route`` may use: ``(start edge, choice)``.

    Flow's name ``route{start}_{i}`` (choice ``i``; ``_0`` for a start edge's only route) and
    flowrun's SUMO id (:func:`route_name`).
    """
    out: dict[str, tuple[str, int | None]] = {}
    for start in dict.fromkeys((*spec.routes, *spec.route_choices)):
        n = len(spec.choices(start))
        for i in range(n):
            out[f"route{start}_{i}"] = (start, i if n > 1 else None)
            if n > 1:
                out[route_name(start, i)] = (start, i)
        out[route_name(start)] = (start, None)
    return out


def check_inflow_route(spec: NetworkSpec, route: str, edge: str) -> None:
    """An inflow's ``route`` names a route of the network that starts on its ``edge``.

    Raises:
        ConfigError: an unknown name (with did-you-mean) or a route starting elsewhere.
    """
    names = named_routes(spec)
    if route not in names:
        flow_names = [n for n in names if not n.startswith("route_")]
        raise ConfigError(
            f"no route '{route}'{did_you_mean(route, list(names))}; the network's routes are "
            f"(Flow's names, route<start edge>_<choice>): {', '.join(flow_names)}",
            path="route",
        )
    start = names[route][0]
    if start != edge:
        raise ConfigError(
            f"route '{route}' starts on edge '{start}' but the inflow enters on '{edge}'; "
            f"give edge: {start}",
            path="route",
        )


_RATE_KEYS = (("vehs_per_hour", "vehsPerHour"), ("probability", "probability"),
              ("period", "period"))  # fmt: skip


def flows_xml(spec: NetworkSpec, inflow: Any, index: int) -> list[str]:
    """SUMO ``<flow>`` elements of one inflow: one per route choice of its edge, each with the
    inflow's rate times the choice's probability (a period divided by it); one ``<flow>`` at
    the full rate on the inflow's ``route`` when it names one."""
    choices = spec.choices(inflow.edge) or (((inflow.edge,), 1.0),)
    chosen = getattr(inflow, "route", None)
    picks: list[tuple[int | None, float]] = [
        (j if len(choices) > 1 else None, prob) for j, (_, prob) in enumerate(choices)
    ]
    if chosen is not None:
        picks = [(named_routes(spec)[chosen][1], 1.0)]
    flow_id = f"{inflow.name}_{index}"
    out = []
    for j, prob in picks:
        attrs: dict[str, str] = {
            "id": flow_id if len(picks) == 1 else f"{flow_id}_{j}",
            "type": inflow.veh_type,
            "route": route_name(inflow.edge, j),
            "departLane": str(inflow.depart_lane),
            "departSpeed": str(inflow.depart_speed),
            "begin": repr(float(inflow.begin)),
        }
        for key, sumo_key in _RATE_KEYS:
            value = getattr(inflow, key, None)
            if value is not None:
                rate = float(value) / prob if key == "period" else float(value) * prob
                attrs[sumo_key] = repr(rate)
        number = getattr(inflow, "number", None)
        if number is not None:
            attrs["number"] = str(max(1, round(int(number) * prob)))
        else:
            attrs["end"] = repr(float(inflow.end))
        for key, value in (getattr(inflow, "extra", None) or {}).items():
            attrs[key] = str(value)
        text = " ".join(f"{k}={quoteattr(v)}" for k, v in attrs.items())
        out.append(f"    <flow {text}/>")
    return out
