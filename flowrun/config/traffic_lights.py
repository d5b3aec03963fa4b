"""Traffic-light programs (Flow's ``TrafficLightParams``) as checked, typed data.

``TrafficLightParams(baseline=False).add(node_id, tls_type, programID, offset, phases, maxGap,
detectorGap, showDetectors, file, freq)`` declares the program of the light at a junction, with
Flow's names and defaults. :meth:`TrafficLightParams.programs` resolves them into
:class:`TlsProgram` objects (``baseline=True`` gives every light Flow's 4-phase actuated
program) that :mod:`flowrun.networks.tls` writes as SUMO ``<tlLogic>`` elements. See SUMO's
"Traffic Lights" documentation for the meaning of the fields.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from flowrun.errors import ConfigError
from flowrun.suggest import did_you_mean

#: Flow's defaults of an actuated light: max gap (s), detector gap (s), detectors shown.
MAX_GAP, DETECTOR_GAP, SHOW_DETECTORS = 3.0, 0.6, True
#: Flow's default program id of an added light.
PROGRAM_ID = 10
#: SUMO's signal characters (red, yellow, green, green minor, red-yellow, off, stop...).
STATE_CHARS = frozenset("rRyYgGuoOs")
#: Program types SUMO runs (flowrun checks the ones Flow documents and SUMO's delay-based one).
TLS_TYPES = ("static", "actuated", "delay_based")


@dataclass(frozen=True)
class Phase:
    """One phase of a signal program.

    Attributes:
        duration: seconds the phase lasts (static; the initial duration of an actuated one).
        state: one signal character per controlled link (``G`` green, ``y`` yellow, ``r``
            red, ...), in SUMO's link-index order.
        min_dur: shortest duration of an actuated phase, s.
        max_dur: longest duration of an actuated phase, s.
    """

    duration: float
    state: str
    min_dur: float | None = None
    max_dur: float | None = None


@dataclass(frozen=True)
class TlsProgram:
    """The program of the light at one junction, ready to be written for SUMO.

    Attributes:
        node_id: the junction (and traffic-light) id.
        tls_type: ``static``, ``actuated`` or ``delay_based``.
        program_id: SUMO program id.
        offset: time shift of the program's start, s.
        phases: the phases; empty means SUMO's default phases of that junction.
        params: SUMO ``<param>`` values (actuated: ``max-gap``, ``detector-gap``, ...).
    """

    node_id: str
    tls_type: str
    program_id: str
    offset: float
    phases: tuple[Phase, ...]
    params: tuple[tuple[str, str], ...] = ()


def _number(value: Any, path: str, positive: bool = True) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"expected a number of seconds, got {value!r}", path=path) from None
    if isinstance(value, bool) or number != number or (positive and number <= 0):
        raise ConfigError(f"expected a number of seconds > 0, got {value!r}", path=path)
    return number


_PHASE_KEYS = ("duration", "state", "minDur", "maxDur")


def parse_phase(raw: Mapping[str, Any], path: str) -> Phase:
    """A :class:`Phase` from Flow's dict ``{duration, state[, minDur, maxDur]}``.

    Raises:
        ConfigError: unknown key, missing duration/state, a duration <= 0, an empty state or
            one with characters SUMO does not know, or ``minDur > maxDur``.
    """
    if not isinstance(raw, Mapping):
        raise ConfigError(f"expected a phase {{duration, state}}, got {raw!r}", path=path)
    for key in raw:
        if key not in _PHASE_KEYS:
            raise ConfigError(
                f"unknown phase key {key!r}{did_you_mean(str(key), _PHASE_KEYS)}; "
                f"expected: {', '.join(_PHASE_KEYS)}",
                path=f"{path}.{key}",
            )
    for key in ("duration", "state"):
        if key not in raw:
            raise ConfigError(f"a phase needs '{key}'", path=path)
    state = raw["state"]
    if not isinstance(state, str) or not state:
        raise ConfigError(f"expected a signal state string like 'GrGr', got {state!r}",
                          path=f"{path}.state")  # fmt: skip
    bad = sorted(set(state) - STATE_CHARS)
    if bad:
        raise ConfigError(
            f"unknown signal character(s) {', '.join(map(repr, bad))} in state {state!r}; "
            f"SUMO knows {''.join(sorted(STATE_CHARS))} (G green, y yellow, r red, ...)",
            path=f"{path}.state",
        )
    min_dur = None if raw.get("minDur") is None else _number(raw["minDur"], f"{path}.minDur")
    max_dur = None if raw.get("maxDur") is None else _number(raw["maxDur"], f"{path}.maxDur")
    if min_dur is not None and max_dur is not None and min_dur > max_dur:
        raise ConfigError(f"minDur {min_dur} > maxDur {max_dur}", path=f"{path}.minDur")
    return Phase(_number(raw["duration"], f"{path}.duration"), state, min_dur, max_dur)


class TrafficLightParams:
    """Traffic lights of a network (Flow's ``TrafficLightParams``).

    Args:
        baseline: give every traffic-light junction Flow's actuated default program
            (:meth:`actuated_default`) unless :meth:`add` describes it.
    """

    def __init__(self, baseline: bool = False) -> None:
        self.baseline = baseline
        self._tls: dict[str, dict[str, Any]] = {}

    def add(
        self,
        node_id: str,
        tls_type: str = "static",
        programID: str | int = PROGRAM_ID,  # Flow's camelCase names
        offset: float | None = None,
        phases: Sequence[Mapping[str, Any]] | None = None,
        maxGap: float | None = None,
        detectorGap: float | None = None,
        showDetectors: bool | None = None,
        file: str | None = None,
        freq: float | None = None,
    ) -> None:
        """Describe the light at ``node_id`` (Flow's arguments and defaults).

        Raises:
            ConfigError: unknown ``tls_type`` or an invalid phase (checked here, at once).
        """
        path = f"traffic_lights.{node_id}"
        if tls_type not in TLS_TYPES:
            raise ConfigError(
                f"unknown tls_type {tls_type!r}{did_you_mean(str(tls_type), TLS_TYPES)}; "
                f"expected one of {', '.join(TLS_TYPES)}",
                path=f"{path}.tls_type",
            )
        for i, raw in enumerate(phases or ()):
            parse_phase(raw, f"{path}.phases[{i}]")
        props: dict[str, Any] = {"id": node_id, "type": tls_type}
        if programID is not None:
            props["programID"] = programID
        if offset:
            props["offset"] = offset
        if phases:
            props["phases"] = [dict(p) for p in phases]
        if tls_type == "actuated":
            props["max-gap"] = maxGap if maxGap else MAX_GAP
            props["detector-gap"] = detectorGap if detectorGap else DETECTOR_GAP
            props["show-detectors"] = showDetectors if showDetectors is not None \
                else SHOW_DETECTORS  # fmt: skip
            if file:
                props["file"] = file
            if freq:
                props["freq"] = freq
        self._tls[node_id] = props

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, TrafficLightParams)
            and self.baseline == other.baseline
            and self._tls == other._tls
        )

    __hash__ = None  # type: ignore[assignment]  # mutable, like Flow's

    def __repr__(self) -> str:
        return f"TrafficLightParams(baseline={self.baseline!r}, lights={self._tls!r})"

    def get_properties(self) -> dict[str, dict[str, Any]]:
        """Every added light as Flow's dict (``id, type, programID, offset, phases, max-gap,
        detector-gap, show-detectors, file, freq``), by node id."""
        return {k: dict(v) for k, v in self._tls.items()}

    @staticmethod
    def actuated_default() -> dict[str, Any]:
        """Flow's default actuated program: GrGr 31 s [8, 45], yryr 6 s [3, 6], rGrG 31 s
        [8, 45], ryry 6 s [3, 6]; program 1, max gap 3.0 s, detector gap 0.8 s."""
        phases = [
            {"duration": "31", "minDur": "8", "maxDur": "45", "state": "GrGr"},
            {"duration": "6", "minDur": "3", "maxDur": "6", "state": "yryr"},
            {"duration": "31", "minDur": "8", "maxDur": "45", "state": "rGrG"},
            {"duration": "6", "minDur": "3", "maxDur": "6", "state": "ryry"},
        ]
        return {"tl_type": "actuated", "program_id": "1", "max_gap": "3.0",
                "detector_gap": "0.8", "show_detectors": True, "phases": phases}  # fmt: skip

    def programs(self, tl_nodes: Iterable[str]) -> list[TlsProgram]:
        """The programs to load, for a network whose traffic-light junctions are
        ``tl_nodes``: the added lights, and with ``baseline`` the actuated default on the rest.

        Raises:
            ConfigError: a light was added on a node that is not a traffic-light junction.
        """
        nodes = list(tl_nodes)
        out = []
        for node_id, props in self._tls.items():
            if node_id not in nodes:
                hint = did_you_mean(node_id, nodes) if nodes else ""
                where = f"its lights are at {', '.join(nodes)}" if nodes else "it has none"
                raise ConfigError(
                    f"no traffic-light junction {node_id!r} in the network{hint}; {where} "
                    "(a light goes on a junction node of the network)",
                    path=f"traffic_lights.{node_id}",
                )
            out.append(_program(node_id, props))
        if self.baseline:
            default = self.actuated_default()
            props = {"type": "actuated", "programID": default["program_id"],
                     "phases": default["phases"], "max-gap": default["max_gap"],
                     "detector-gap": default["detector_gap"],
                     "show-detectors": default["show_detectors"]}  # fmt: skip
            out += [_program(n, props) for n in nodes if n not in self._tls]
        return out


_PARAM_KEYS = ("max-gap", "detector-gap", "show-detectors", "file", "freq")


def _program(node_id: str, props: Mapping[str, Any]) -> TlsProgram:
    path = f"traffic_lights.{node_id}"
    phases = tuple(
        parse_phase(p, f"{path}.phases[{i}]") for i, p in enumerate(props.get("phases") or ())
    )
    params = []
    for key in _PARAM_KEYS:
        value = props.get(key)
        if value is not None:
            text = str(value).lower() if isinstance(value, bool) else str(value)
            params.append((key, text))
    offset = props.get("offset") or 0
    return TlsProgram(
        node_id,
        str(props.get("type", "static")),
        str(props.get("programID", PROGRAM_ID)),
        _number(offset, f"{path}.offset", positive=False),
        phases,
        tuple(params),
    )
