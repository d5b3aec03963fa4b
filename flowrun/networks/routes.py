"""The ``.rou.xml`` of an episode: vehicle types, routes and inflows."""

from __future__ import annotations

from typing import Any
from xml.sax.saxutils import quoteattr

from flowrun.config.params import VehicleParams
from flowrun.config.vtype import vtype_attributes
from flowrun.networks.spec import NetworkSpec


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


_RATE_KEYS = (("vehs_per_hour", "vehsPerHour"), ("probability", "probability"),
              ("period", "period"))  # fmt: skip


def flows_xml(spec: NetworkSpec, inflow: Any, index: int) -> list[str]:
    """SUMO ``<flow>`` elements of one inflow: one per route choice of its edge, each with the
    inflow's rate times the choice's probability (a period divided by it)."""
    choices = spec.choices(inflow.edge) or (((inflow.edge,), 1.0),)
    flow_id = f"{inflow.name}_{index}"
    out = []
    for j, (_, prob) in enumerate(choices):
        attrs: dict[str, str] = {
            "id": flow_id if len(choices) == 1 else f"{flow_id}_{j}",
            "type": inflow.veh_type,
            "route": route_name(inflow.edge, j if len(choices) > 1 else None),
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
