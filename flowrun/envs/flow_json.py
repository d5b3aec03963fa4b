"""A Flow ``flow_params`` dict to JSON and back (Flow's ``flow.utils.rllib``).

Flow stores an experiment's ``flow_params`` as JSON with :class:`FlowParamsEncoder`
(``json.dumps(flow_params, cls=FlowParamsEncoder)``, e.g. in RLlib's ``env_config``) and
rebuilds it with :func:`get_flow_params`. Both follow Flow's layout: classes by name, each
vehicle group as a dict whose controllers are ``[class name, params]`` and whose
car-following / lane-change parameters are ``{"controller_params": {...SUMO names...},
"speed_mode" | "lane_change_mode": int}``, the other parameter objects as their attributes
(inflows and traffic lights under Flow's private attribute names). So a JSON file written by
Flow loads here, and one written here loads here with every flowrun field.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import re
from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

import flowrun.envs
import flowrun.networks
from flowrun.config.params import (
    EnvParams,
    InFlows,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    TrafficLightParams,
    VehicleParams,
)
from flowrun.config.vehicles import controller_tuple

log = logging.getLogger(__name__)

#: Flow's private attribute names (``obj.__dict__`` of its ``InFlows`` / ``TrafficLightParams``)
FLOWS_KEY = "_InFlows__flows"
TLS_KEY = "_TrafficLightParams__tls_properties"

#: SUMO's spelling -> the parameter classes' keyword, where the generic rule does not fit
_SPECIAL = {"laneChangeModel": "model", "lcLookaheadLeft": "lc_look_ahead_left"}


class FlowParamsEncoder(json.JSONEncoder):
    """JSON encoder for Flow's ``flow_params`` (Flow's ``FlowParamsEncoder``).

    Classes and functions become their names; :class:`VehicleParams` a list of group dicts;
    the other parameter objects their attributes.
    """

    def default(self, o: Any) -> Any:
        """The JSON form of ``o`` (see the class docstring)."""
        if isinstance(o, VehicleParams):
            return [_group(g) for g in o.groups]
        if isinstance(o, InFlows):
            return {FLOWS_KEY: [_inflow(f) for f in o.get()]}
        if isinstance(o, TrafficLightParams):
            return {"baseline": o.baseline, TLS_KEY: o.get_properties()}
        if isinstance(o, SumoCarFollowingParams):
            return {"controller_params": o.controller_params, "speed_mode": int(o.speed_mode),
                    **_fields(o)}  # fmt: skip
        if isinstance(o, SumoLaneChangeParams):
            return {"controller_params": o.controller_params,
                    "lane_change_mode": int(o.lane_change_mode), **_fields(o)}  # fmt: skip
        if dataclasses.is_dataclass(o) and not isinstance(o, type):
            return _fields(o)
        if hasattr(o, "__name__"):
            return o.__name__
        if hasattr(o, "__dict__"):
            return {k: v for k, v in vars(o).items() if not k.startswith("_")}
        return super().default(o)


def get_flow_params(config: Mapping[str, Any] | str | Path) -> dict[str, Any]:
    """Flow's ``flow_params`` dict, with parameter objects, from its JSON form.

    Args:
        config: RLlib's stored configuration (a dict whose ``env_config["flow_params"]`` is
            the JSON text), or the path of a ``flow_params`` JSON file.

    Returns:
        ``flow_params`` with ``sim``, ``env``, ``net``, ``veh``, ``initial`` and ``tls`` as
        flowrun's parameter objects; ``env_name`` and ``network`` as the classes flowrun has
        under those names (the names themselves otherwise).
    """
    if isinstance(config, Mapping):
        data = json.loads(config["env_config"]["flow_params"])
    else:
        data = json.loads(Path(config).read_text(encoding="utf-8"))
    out = dict(data)
    out["veh"] = _vehicles(data.get("veh") or [])
    out["sim"] = _build(SumoParams, data.get("sim") or {})
    out["env"] = _build(EnvParams, data.get("env") or {})
    net = dict(data.get("net") or {})
    flows = (net.pop("inflows", None) or {}).get(FLOWS_KEY, [])
    out["net"] = _build(NetParams, {**net, "inflows": _inflows(flows)})
    out["initial"] = _build(InitialConfig, data.get("initial") or {})
    out["tls"] = _tls(data.get("tls") or {})
    out["env_name"] = _class_named(flowrun.envs, data.get("env_name"))
    out["network"] = _class_named(flowrun.networks, data.get("network"))
    return out


# ---------------------------------------------------------------------- encoding helpers
def _fields(obj: Any) -> dict[str, Any]:
    return {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}


def _controller(spec: Any) -> list[Any] | None:
    pair = controller_tuple(spec)
    if pair is None:
        return None
    cls, params = pair
    return [getattr(cls, "__name__", str(cls)), params]


def _group(g: Any) -> dict[str, Any]:
    return {
        "veh_id": g.veh_id,
        "acceleration_controller": _controller(g.acceleration_controller),
        "lane_change_controller": _controller(g.lane_change_controller),
        "routing_controller": _controller(g.routing_controller),
        "initial_speed": g.initial_speed,
        "num_vehicles": g.num_vehicles,
        "car_following_params": g.car_following_params,
        "lane_change_params": g.lane_change_params,
        "color": g.color,
    }


def _inflow(f: Any) -> dict[str, Any]:
    return {k: v for k, v in _fields(f).items() if v is not None}


# ---------------------------------------------------------------------- decoding helpers
def _snake(key: str) -> str:
    return _SPECIAL.get(key) or re.sub(r"([A-Z])", r"_\1", key).lower()


def _build(cls: type, given: Mapping[str, Any]) -> Any:
    """``cls(**given)`` for the keys ``cls`` has (Flow's other attributes are left out)."""
    names = {f.name for f in dataclasses.fields(cls)}
    kept = {k: v for k, v in given.items() if k in names}
    dropped = sorted(set(given) - names)
    if dropped:
        log.debug("%s: ignoring Flow attributes flowrun does not model: %s", cls.__name__, dropped)
    return cls(**kept)


def _sumo_params(cls: type, given: Mapping[str, Any], mode_key: str) -> Any:
    values: dict[str, Any] = {}
    for key, value in (given.get("controller_params") or {}).items():
        values[_snake(key)] = float(value) if key.startswith("lc") else value
    values.update({k: v for k, v in given.items() if k != "controller_params"})
    if mode_key in given:
        values[mode_key] = given[mode_key]
    return _build(cls, values)


def _vehicles(groups: list[Mapping[str, Any]]) -> VehicleParams:
    veh = VehicleParams()
    for g in groups:
        veh.add(
            g["veh_id"],
            acceleration_controller=_controller_arg(g.get("acceleration_controller")),
            lane_change_controller=_controller_arg(g.get("lane_change_controller")),
            routing_controller=_controller_arg(g.get("routing_controller")),
            initial_speed=g.get("initial_speed", 0.0),
            num_vehicles=g.get("num_vehicles", 0),
            car_following_params=_sumo_params(
                SumoCarFollowingParams, g.get("car_following_params") or {}, "speed_mode"
            ),
            lane_change_params=_sumo_params(
                SumoLaneChangeParams, g.get("lane_change_params") or {}, "lane_change_mode"
            ),
            color=g.get("color"),
        )
    return veh


def _controller_arg(pair: Any) -> tuple[Any, dict[str, Any]] | None:
    if not pair:
        return None
    from flowrun.controllers.registry import resolve_controller

    name, params = pair[0], dict(pair[1] or {})
    return resolve_controller(name), params


def _inflows(flows: list[Mapping[str, Any]]) -> InFlows | None:
    if not flows:
        return None
    inflows = InFlows()
    for f in flows:
        given = dict(f)
        extra = dict(given.pop("extra", None) or {})
        given.pop("name", None)  # Flow's stored "flow_0" names come back from the index
        inflows.add(given.pop("edge"), given.pop("veh_type", given.pop("vtype", "")),
                    **given, **extra)  # fmt: skip
    return inflows


def _tls(given: Mapping[str, Any]) -> TrafficLightParams:
    tls = TrafficLightParams(baseline=bool(given.get("baseline", False)))
    for node_id, props in (given.get(TLS_KEY) or {}).items():
        props = {k: v for k, v in props.items() if k != "id"}
        if "type" in props:
            props["tls_type"] = props.pop("type")
        tls.add(node_id, **props)
    return tls


def _class_named(module: ModuleType, name: Any) -> Any:
    if not isinstance(name, str):
        return name
    return getattr(module, name, name)


__all__ = ["FlowParamsEncoder", "get_flow_params"]
