"""The ``traffic_lights:`` section as YAML: plain data <-> :class:`TrafficLightsConfig`.

```yaml
traffic_lights:
  baseline: false          # Flow's TrafficLightParams(baseline=...)
  controller: null         # fixed_time | actuated | max_pressure (flowrun baseline)
  min_green: 8             # s, max_pressure
  yellow: 3                # s, fixed_time and max_pressure
  lights:                  # each: the arguments of TrafficLightParams.add, Flow's names
    - {node_id: center0, tls_type: static, programID: 10, offset: 0,
       phases: [{duration: 31, state: GrGr}, {duration: 3, state: yryr}, ...]}
```
Phases take Flow's keys (``duration, state, minDur, maxDur``). A state's length is checked
against the junction once the network is built (:mod:`flowrun.loading.loader`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from flowrun.config.signal_control import CONTROLLERS, TrafficLightsConfig
from flowrun.config.traffic_lights import TrafficLightParams
from flowrun.config.yamlio import KeyPath, Locations
from flowrun.errors import ConfigError
from flowrun.suggest import did_you_mean

SECTION_KEYS = ("baseline", "controller", "min_green", "yellow", "lights")
LIGHT_KEYS = ("node_id", "tls_type", "programID", "offset", "phases", "maxGap", "detectorGap",
              "showDetectors", "file", "freq")  # fmt: skip
#: Light keys that only an actuated program takes, and their ``get_properties`` names.
ACTUATED_KEYS = {"maxGap": "max-gap", "detectorGap": "detector-gap",
                 "showDetectors": "show-detectors", "file": "file", "freq": "freq"}  # fmt: skip
_NUMBERS = ("offset", "maxGap", "detectorGap", "freq")


def _show(value: Any) -> str:
    if isinstance(value, Mapping):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    return "null" if value is None else repr(value)


def _number(loc: Locations, value: Any, at: KeyPath, low: float = 0.0) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not value >= low:
        raise loc.error(f"expected a number >= {low:g}, got {_show(value)}", at)
    return float(value)


def parse_traffic_lights(loc: Locations, data: Any, path: KeyPath) -> TrafficLightsConfig:
    """``traffic_lights:`` data -> :class:`TrafficLightsConfig` (errors at ``file:line``).

    Raises:
        ConfigError: an unknown key (with did-you-mean), a wrong type, an unknown controller,
            a light twice, or a bad program (unknown ``tls_type``, phase key or signal
            character; ``minDur > maxDur``); an actuated key on a static light.
    """
    if data is None:
        return TrafficLightsConfig()
    if not isinstance(data, Mapping):
        raise loc.error(f"expected a mapping ({', '.join(SECTION_KEYS)}), got {_show(data)}",
                        path)  # fmt: skip
    for key in data:
        if key not in SECTION_KEYS:
            hint = did_you_mean(str(key), SECTION_KEYS)
            raise loc.error(f"unknown key '{key}'{hint}; expected one of: "
                            f"{', '.join(SECTION_KEYS)}", (*path, key))  # fmt: skip
    baseline = data.get("baseline", False)
    if not isinstance(baseline, bool):
        raise loc.error(f"expected true or false, got {_show(baseline)}", (*path, "baseline"))
    controller = data.get("controller")
    if controller is not None and controller not in CONTROLLERS:
        hint = did_you_mean(str(controller), CONTROLLERS)
        raise loc.error(f"unknown signal controller {_show(controller)}{hint}; expected one of "
                        f"{', '.join(CONTROLLERS)} (or null)", (*path, "controller"))  # fmt: skip
    default = TrafficLightsConfig()
    min_green = _number(loc, data.get("min_green", default.min_green), (*path, "min_green"))
    yellow = _number(loc, data.get("yellow", default.yellow), (*path, "yellow"))
    lights = data.get("lights")
    if lights is None:
        lights = []
    if not isinstance(lights, list):
        raise loc.error(f"expected a list of lights (- node_id: ..., phases: ...), got "
                        f"{_show(lights)}", (*path, "lights"))  # fmt: skip
    programs = TrafficLightParams(baseline=baseline)
    seen: dict[str, int] = {}
    for i, raw in enumerate(lights):
        node = _add_light(loc, programs, raw, (*path, "lights", i))
        if node in seen:
            raise loc.error(f"light {node!r} is declared twice (also lights[{seen[node]}])",
                            (*path, "lights", i, "node_id"))  # fmt: skip
        seen[node] = i
    if controller is not None and (seen or baseline):
        given = "lights" if seen else "baseline"
        raise loc.error(f"controller {controller} sets every light's program itself; remove "
                        f"'{given}' or the controller", (*path, "controller"))  # fmt: skip
    return TrafficLightsConfig(programs, controller, min_green, yellow)


def _add_light(loc: Locations, programs: TrafficLightParams, raw: Any, at: KeyPath) -> str:
    if not isinstance(raw, Mapping):
        raise loc.error(f"expected a light (node_id: ..., phases: [...]), got {_show(raw)}", at)
    for key in raw:
        if key not in LIGHT_KEYS:
            raise loc.error(f"unknown key '{key}'{did_you_mean(str(key), LIGHT_KEYS)}; expected "
                            f"one of: {', '.join(LIGHT_KEYS)}", (*at, key))  # fmt: skip
    node = raw.get("node_id")
    if not isinstance(node, str) or not node:
        raise loc.error("a light needs 'node_id', the junction's id", (*at, "node_id")
                        if "node_id" in raw else at)  # fmt: skip
    tls_type = raw.get("tls_type", "static")
    if tls_type != "actuated":
        for key in ACTUATED_KEYS:
            if key in raw:
                raise loc.error(f"'{key}' applies to actuated lights only (this one is "
                                f"{tls_type})", (*at, key))  # fmt: skip
    for key in _NUMBERS:
        if raw.get(key) is not None:
            _number(loc, raw[key], (*at, key))
    program_id = raw.get("programID", 10)
    if isinstance(program_id, bool) or not isinstance(program_id, str | int):
        raise loc.error(f"expected a string or an integer, got {_show(program_id)}",
                        (*at, "programID"))  # fmt: skip
    phases = raw.get("phases")
    if phases is not None and not isinstance(phases, list):
        raise loc.error(f"expected a list of phases, got {_show(phases)}", (*at, "phases"))
    show = raw.get("showDetectors")
    if show is not None and not isinstance(show, bool):
        raise loc.error(f"expected true or false, got {_show(show)}", (*at, "showDetectors"))
    kwargs = {k: v for k, v in raw.items() if k != "node_id"}
    try:
        programs.add(node, **kwargs)
    except ConfigError as err:
        raise loc.error(err.message, (*at, *light_subpath(err.path, node))) from None
    return node


def light_subpath(path: str, node: str) -> KeyPath:
    """``traffic_lights.center0.phases[1].state`` -> ``("phases", 1, "state")``."""
    from flowrun.config.overrides import parse_key

    prefix = f"traffic_lights.{node}"
    rest = path[len(prefix):].lstrip(".") if path.startswith(prefix) else ""
    if not rest:
        return ("node_id",) if path == prefix else ()
    return parse_key(rest)


def traffic_lights_data(tls: TrafficLightsConfig) -> dict[str, Any]:
    """The section as plain YAML data (``parse_traffic_lights`` gives an equal config back)."""
    lights = []
    for node, props in tls.programs.get_properties().items():
        light: dict[str, Any] = {"node_id": node, "tls_type": props.get("type", "static")}
        if "programID" in props:
            light["programID"] = props["programID"]
        if props.get("offset"):
            light["offset"] = props["offset"]
        if props.get("phases"):
            light["phases"] = [dict(p) for p in props["phases"]]
        for key, name in ACTUATED_KEYS.items():
            if props.get(name) is not None:
                light[key] = props[name]
        lights.append(light)
    return {"baseline": tls.programs.baseline, "controller": tls.controller,
            "min_green": tls.min_green, "yellow": tls.yellow, "lights": lights}  # fmt: skip
