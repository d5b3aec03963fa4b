"""Inflows (Flow's ``InFlows``): vehicles of one type entering an edge at a rate.

One :class:`InFlow` is one SUMO ``<flow>`` element. ``InFlows.add`` takes Flow's arguments
(``edge, veh_type, vehs_per_hour | probability | period, depart_lane, depart_speed, name,
begin, end, number, **kwargs``) with Flow's semantics; YAML ``network.inflows: [...]`` builds
the same objects with the same checks (see :mod:`flowrun.config.convert`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

from flowrun.errors import ConfigError

#: The three ways to give an inflow's rate; exactly one is required.
RATES = ("vehs_per_hour", "probability", "period")

#: Flow's deprecated camelCase keywords -> today's names (accepted with a DeprecationWarning).
CAMEL_CASE = {
    "vehsPerHour": "vehs_per_hour",
    "departLane": "depart_lane",
    "departSpeed": "depart_speed",
}

#: SUMO ``<flow>`` attribute of each field that maps to one.
SUMO_NAMES = {
    "vehs_per_hour": "vehsPerHour",
    "probability": "probability",
    "period": "period",
    "depart_lane": "departLane",
    "depart_speed": "departSpeed",
    "begin": "begin",
    "end": "end",
    "number": "number",
}


@dataclass(frozen=True)
class InFlow:
    """One inflow: what SUMO's ``<flow>`` needs.

    Attributes:
        edge: the edge vehicles enter on (must be an edge of the network). Their route is
            the network's route (or route choices) for that start edge.
        veh_type: the vehicle group (``VehicleParams`` ``veh_id``) the vehicles belong to:
            SUMO ``type``; the group's controllers drive them from their first step.
        vehs_per_hour: vehicles per hour, evenly spaced (SUMO ``vehsPerHour``).
        probability: chance of a departure each second, 0..1 (SUMO ``probability``).
        period: seconds between two departures (SUMO ``period``). Exactly one of
            ``vehs_per_hour``, ``probability`` and ``period`` is set.
        depart_lane: lane index or a SUMO keyword (``first``, ``free``, ``random``, ``best``,
            ...) (SUMO ``departLane``).
        depart_speed: m/s or a SUMO keyword (``max``, ``random``, ``desired``, ...)
            (SUMO ``departSpeed``).
        name: prefix of the flow id. As in Flow the SUMO flow id is ``{name}_{index}``
            (``index`` = position in :class:`InFlows`, see :meth:`InFlows.sumo_ids`) and its
            vehicles are ``{name}_{index}.{k}``.
        begin: first departure time, s (at least 1, as in Flow: vehicles placed at reset come
            first).
        end: last departure time, s. Ignored when ``number`` is set.
        number: total vehicles of this flow; replaces ``end`` (SUMO ``number``).
        route: one route of the network by name, which every vehicle of this flow drives
            (Flow's ``InFlows.add(..., route="routehighway_0_0")``: Flow names the routes
            ``route{start edge}_{choice}``); it must start on ``edge``. ``None`` spreads the
            flow over the edge's route choices by their probabilities.
        extra: further SUMO ``<flow>`` attributes passed as they are (``color``,
            ``departPos``, ``arrivalPos``, ...), SUMO's own spelling; values written with
            ``str``.
    """

    edge: str
    veh_type: str
    vehs_per_hour: float | None = None
    probability: float | None = None
    period: float | None = None
    depart_lane: str | int = "first"
    depart_speed: str | float = 0.0
    name: str = "flow"
    begin: float = 1.0
    end: float = 86400.0
    number: int | None = None
    route: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        problem = inflow_problem(self)
        if problem is not None:
            raise ConfigError(problem[1], path=problem[0])

    def sumo_attributes(self, index: int) -> dict[str, str]:
        """The ``<flow>`` attributes (SUMO spelling, string values) of the ``index``-th flow.

        ``id`` is ``{name}_{index}``; ``end`` is left out when ``number`` is set; the route
        (``route``/``from``) is the writer's to add.
        """
        out = {"id": f"{self.name}_{index}", "type": self.veh_type}
        for name, sumo in SUMO_NAMES.items():
            value = getattr(self, name)
            if value is None or (name == "end" and self.number is not None):
                continue
            out[sumo] = _sumo_str(value)
        out.update({str(k): _sumo_str(v) for k, v in self.extra.items()})
        return out


def _sumo_str(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _unset_or(value: float | None, low: float, high: float) -> bool:
    """``value`` is not given, or ``low < value <= high``."""
    return value is None or low < value <= high


def inflow_problem(flow: InFlow) -> tuple[str, str] | None:
    """What is wrong with an inflow: ``(field, message)``, or ``None`` when it is fine."""
    given = [r for r in RATES if getattr(flow, r) is not None]
    if len(given) != 1:
        found = f"got {' and '.join(given)}" if given else "got none"
        return (
            given[1] if len(given) > 1 else "vehs_per_hour",
            "an inflow needs exactly one of vehs_per_hour, probability or period; " + found,
        )
    checks: list[tuple[str, bool, str]] = [
        ("vehs_per_hour", _unset_or(flow.vehs_per_hour, 0, math.inf), "must be greater than 0"),
        ("probability", _unset_or(flow.probability, 0, 1), "must be in (0, 1]"),
        ("period", _unset_or(flow.period, 0, math.inf), "must be greater than 0"),
        ("begin", flow.begin >= 1, "must be at least 1 s (cars placed at reset come first)"),
        ("end", flow.number is not None or flow.end >= flow.begin, "must not be before begin"),
        ("number", flow.number is None or flow.number >= 1, "must be at least 1"),
        ("edge", bool(flow.edge), "must not be empty"),
        ("veh_type", bool(flow.veh_type), "must not be empty"),
        ("name", bool(flow.name), "must not be empty"),
        ("route", flow.route is None or bool(flow.route), "must name a route"),
    ]
    for name, ok, message in checks:
        if not ok:
            return name, f"{message}, got {getattr(flow, name)!r}"
    clash = sorted(set(flow.extra) & {"id", "type", "route", "from", *SUMO_NAMES.values()})
    if clash:
        return "extra", f"{', '.join(clash)} must be given as InFlow fields, not in extra"
    return None


class InFlows:
    """Inflows of vehicles into an open network (Flow's ``InFlows``).

    Args:
        flows: inflows to start with (the YAML loader passes them).
    """

    def __init__(self, flows: list[InFlow] | None = None) -> None:
        self.flows: list[InFlow] = list(flows or [])

    def add(
        self,
        edge: str,
        veh_type: str,
        vehs_per_hour: float | None = None,
        probability: float | None = None,
        period: float | None = None,
        depart_lane: str | int = "first",
        depart_speed: str | float = 0,
        name: str = "flow",
        begin: float = 1,
        end: float = 86400,
        number: int | None = None,
        **kwargs: Any,
    ) -> None:
        """Add an inflow of ``veh_type`` vehicles entering ``edge`` (Flow's signature).

        Give exactly one of ``vehs_per_hour``, ``probability`` (per second) and ``period``
        (s). ``number`` caps the vehicles and replaces ``end``. Other keywords are SUMO
        ``<flow>`` attributes (``color``, ``departPos``, ...) and are passed on as given;
        Flow's old ``vehsPerHour``, ``departLane`` and ``departSpeed`` still work (with a
        ``DeprecationWarning``). ``route`` (a SUMO attribute Flow passes on) picks one of the
        network's routes by name (:attr:`InFlow.route`). See :class:`InFlow` for every field.

        Raises:
            ConfigError: no rate or more than one, ``begin < 1``, or another bad value.
        """
        values: dict[str, Any] = {
            "vehs_per_hour": vehs_per_hour,
            "depart_lane": depart_lane,
            "depart_speed": depart_speed,
        }
        for old, new in CAMEL_CASE.items():
            if old in kwargs:
                warnings.warn(
                    f"InFlows.add: '{old}' is deprecated; use '{new}'",
                    DeprecationWarning,
                    stacklevel=2,
                )
                values[new] = kwargs.pop(old)
        self.flows.append(
            InFlow(
                edge=edge,
                veh_type=veh_type,
                probability=probability,
                period=period,
                name=name,
                begin=float(begin),
                end=float(end),
                number=number,
                route=kwargs.pop("route", None),
                extra=dict(kwargs),
                **values,
            )
        )

    @property
    def num_flows(self) -> int:
        """Number of inflows (Flow's attribute)."""
        return len(self.flows)

    def get(self) -> list[InFlow]:
        """All inflows, in the order they were added."""
        return list(self.flows)

    def sumo_ids(self) -> list[str]:
        """SUMO flow id of each inflow: ``{name}_{index}``, as Flow names them."""
        return [f"{f.name}_{i}" for i, f in enumerate(self.flows)]

    def __eq__(self, other: object) -> bool:
        return isinstance(other, InFlows) and self.flows == other.flows

    def __repr__(self) -> str:
        return f"InFlows({self.flows!r})"
