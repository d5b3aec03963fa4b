"""Plain YAML data -> the typed parameter objects, one field at a time.

The dataclasses are the schema: a field's type hint says what a YAML value must be, its
default is what an omitted key means, and the class's ``YAML_KEYS`` give the short spellings
(the field name is accepted too). Every error is a :class:`ConfigError` at the key path and
``file:line`` of the offending key.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
import types
from collections.abc import Mapping
from typing import Any, Union, get_args, get_origin, get_type_hints

from flowrun.config.checks import FIELD_CHECKS, INFINITE_OK, NETWORK_NUMBERS, WHOLE_OR_INF
from flowrun.config.inflows import CAMEL_CASE
from flowrun.config.model import NetworkConfig
from flowrun.config.params import (
    ControllerSpec,
    InFlow,
    InFlows,
    NetParams,
    VehicleParams,
    VehicleType,
)
from flowrun.config.signal_control import TrafficLightsConfig
from flowrun.config.tls_yaml import parse_traffic_lights
from flowrun.config.yamlio import KeyPath, Locations
from flowrun.errors import ConfigError
from flowrun.suggest import did_you_mean

#: Largest number in a free-form parameter mapping (network or controller parameters).
MAX_PARAMETER = 1e9
# ``network:`` keys that are not the network type's ``additional_params``.
NETWORK_KEYS = ("type", "inflows", "template", "osm_path")


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return get_type_hints(cls)


def yaml_key(cls: type, field_name: str) -> str:
    """The YAML spelling of a field (its ``YAML_KEYS`` alias, else the field name)."""
    for key, name in getattr(cls, "YAML_KEYS", {}).items():
        if name == field_name:
            return str(key)
    return field_name


def show(value: Any) -> str:
    """A short description of a value found where something else was expected."""
    if value is None:
        return "null"
    if isinstance(value, Mapping):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)


def _describe(tp: Any) -> str:
    names = {
        bool: "true or false",
        int: "an integer",
        float: "a number",
        str: "a string",
        type(None): "null",
    }
    if tp in names:
        return names[tp]
    origin = get_origin(tp)
    if origin in (Union, types.UnionType):
        return " or ".join(_describe(a) for a in get_args(tp))
    if origin is list:
        return "a list"
    return "a mapping"


class Converter:
    """Builds typed values from plain data, raising located errors.

    Args:
        locations: where each key path of the data stands.
    """

    def __init__(self, locations: Locations) -> None:
        self.loc = locations

    def value(self, tp: Any, data: Any, path: KeyPath) -> Any:
        """Convert ``data`` to type ``tp`` (a type hint of a parameter field)."""
        origin = get_origin(tp)
        if origin in (Union, types.UnionType):
            return self._union(tp, data, path)
        if tp is Any:
            return copy.deepcopy(data)
        if tp in (bool, int, float, str):
            return self._scalar(tp, data, path)
        if origin is dict:
            if not isinstance(data, Mapping):
                raise self._expected(tp, data, path)
            return copy.deepcopy(dict(data))
        if origin is list:
            if not isinstance(data, list):
                raise self._expected(tp, data, path)
            (item_tp,) = get_args(tp)
            return [self.value(item_tp, item, (*path, i)) for i, item in enumerate(data)]
        special = {
            ControllerSpec: self.controller,
            VehicleParams: self.vehicles,
            InFlows: self.inflows,
            NetworkConfig: self.network,
            TrafficLightsConfig: self.traffic_lights,
        }
        if tp in special:
            return special[tp](data, path)
        if dataclasses.is_dataclass(tp):
            return self.section(tp, data, path)
        raise TypeError(f"no YAML conversion for {tp!r}")  # a bug in the schema, not the user

    def section(self, cls: Any, data: Any, path: KeyPath) -> Any:
        """Build dataclass ``cls`` from a mapping, checking keys, types and values.

        An empty section (``sim:`` with nothing under it) means all defaults.
        """
        if data is None:
            data = {}
        if not isinstance(data, Mapping):
            raise self.loc.error(f"expected a mapping of settings, got {show(data)}", path)
        fields = {f.name: f for f in dataclasses.fields(cls) if f.metadata.get("yaml", True)}
        accepted = {name: name for name in fields} | dict(getattr(cls, "YAML_KEYS", {}))
        hints = _hints(cls)
        kwargs: dict[str, Any] = {}
        given_as: dict[str, str] = {}
        for key, raw in data.items():
            at = (*path, key)
            name = accepted.get(key) if isinstance(key, str) else None
            old_spelling = getattr(cls, "FLOW_KEYWORDS", {})
            if name is None and key in old_spelling:
                raise self.loc.error(
                    f"'{key}' is Flow's old spelling; write '{yaml_key(cls, old_spelling[key])}'",
                    at,
                )
            if name is None:
                preferred = [yaml_key(cls, f) for f in fields]
                raise self.loc.error(
                    f"unknown key '{key}'{did_you_mean(str(key), accepted)}; "
                    f"expected one of: {', '.join(preferred)}",
                    at,
                )
            if name in kwargs:
                raise self.loc.error(
                    f"'{key}' and '{given_as[name]}' are the same setting; give only one", at
                )
            value = self.value(hints[name], raw, at)
            check = FIELD_CHECKS.get((cls, name))
            # Checked as written (``-3``, not the converted ``-3.0``) so messages quote the file.
            problem = check(raw if type(raw) in (int, float) else value) if check else None
            if problem:
                raise self.loc.error(problem, at)
            if isinstance(value, float) and not math.isfinite(value):
                if math.isnan(value):
                    raise self.loc.error("must be a number, got .nan", at)
                if (cls, name) not in INFINITE_OK:
                    raise self.loc.error(f"must be finite, got {raw!r}", at)
            if (cls, name) in WHOLE_OR_INF and math.isfinite(value):
                value = int(value)  # 3000 steps, not 3000.0 (checked whole above)
            kwargs[name] = value
            given_as[name] = key
        for name, f in fields.items():
            required = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
            if required and name not in kwargs:
                raise self.loc.error(f"missing required key '{yaml_key(cls, name)}'", path)
        return cls(**kwargs)

    def controller(self, data: Any, path: KeyPath) -> ControllerSpec:
        """``IDM`` or ``{type: IDM, v0: 30}`` -> ``ControllerSpec("IDM", {"v0": 30})``."""
        if isinstance(data, str) and data:
            return ControllerSpec(data)
        if not isinstance(data, Mapping):
            raise self.loc.error(
                f"expected a controller name or a mapping with 'type', got {show(data)}", path
            )
        if "type" not in data:
            raise self.loc.error(
                "missing required key 'type' (the controller name, e.g. IDM)", path
            )
        name = data["type"]
        if not isinstance(name, str) or not name:
            raise self.loc.error(f"expected a controller name, got {show(name)}", (*path, "type"))
        params = {k: copy.deepcopy(v) for k, v in data.items() if k != "type"}
        for key, value in params.items():
            self._sane_numbers(value, (*path, key))
        return ControllerSpec(name, params)

    def vehicles(self, data: Any, path: KeyPath) -> VehicleParams:
        """A list of vehicle groups -> :class:`VehicleParams`."""
        if data is None:
            return VehicleParams()
        if not isinstance(data, list):
            raise self.loc.error(
                f"expected a list of vehicle groups (- id: ..., count: ...), got {show(data)}",
                path,
            )
        return VehicleParams(
            [self.section(VehicleType, item, (*path, i)) for i, item in enumerate(data)]
        )

    def inflows(self, data: Any, path: KeyPath) -> InFlows:
        """A list of inflows -> :class:`InFlows`."""
        if not isinstance(data, list):
            raise self.loc.error(
                f"expected a list of inflows (- edge: ..., veh_type: ..., vehs_per_hour: ...), "
                f"got {show(data)}",
                path,
            )
        fields = [f.name for f in dataclasses.fields(InFlow)]
        flows = []
        for i, item in enumerate(data):
            at = (*path, i)
            for key in item if isinstance(item, Mapping) else ():
                if key in CAMEL_CASE:
                    raise self.loc.error(
                        f"'{key}' is Flow's old spelling; write '{CAMEL_CASE[key]}'", (*at, key)
                    )
                if key not in fields:
                    raise self.loc.error(
                        f"unknown key '{key}'{did_you_mean(str(key), fields)}; expected one of: "
                        f"{', '.join(fields)} (other SUMO <flow> attributes go under 'extra')",
                        (*at, key),
                    )
            try:
                flows.append(self.section(InFlow, item, at))
            except ConfigError as err:
                if err.location:  # located already (a type or value check)
                    raise
                # InFlow's own cross-field check (rates, begin/end): at the field it names
                field_at = (*at, err.path) if err.path else at
                raise self.loc.error(err.message, field_at) from None
        return InFlows(flows)

    def network(self, data: Any, path: KeyPath) -> NetworkConfig:
        """``{type: ring, length: 230, ...}`` -> ``NetworkConfig("ring", NetParams({...}))``."""
        if data is None:
            return NetworkConfig()
        if not isinstance(data, Mapping):
            raise self.loc.error(
                f"expected a mapping (type: ring, length: ...), got {show(data)}", path
            )
        kind = data.get("type", NetworkConfig().type)
        if not isinstance(kind, str) or not kind:
            raise self.loc.error(f"expected a network type name, got {show(kind)}", (*path, "type"))
        extra = {k: v for k, v in data.items() if k not in NETWORK_KEYS}
        for key, raw in extra.items():
            if not isinstance(key, str):
                raise self.loc.error(
                    f"a network parameter name must be a string, got {key!r}", path
                )
            if key in NETWORK_NUMBERS:
                tp, check = NETWORK_NUMBERS[key]
                self._scalar(tp, raw, (*path, key))
                problem = check(raw)
                if problem:
                    raise self.loc.error(problem, (*path, key))
            self._sane_numbers(raw, (*path, key))
        hints = _hints(NetParams)
        net = NetParams(
            additional_params=copy.deepcopy(extra),
            inflows=self.value(hints["inflows"], data.get("inflows"), (*path, "inflows")),
            template=self.value(hints["template"], data.get("template"), (*path, "template")),
            osm_path=self.value(hints["osm_path"], data.get("osm_path"), (*path, "osm_path")),
        )
        return NetworkConfig(type=kind, net_params=net)

    def _sane_numbers(self, data: Any, path: KeyPath) -> None:
        """Every number in a free-form parameter (nested too) is finite and at most
        :data:`MAX_PARAMETER` in size: no network or controller wants NaN, inf or 1e308."""
        if isinstance(data, float | int) and not isinstance(data, bool):
            if not abs(data) <= MAX_PARAMETER:  # NaN fails the comparison too
                raise self.loc.error(
                    f"expected a finite number between -{MAX_PARAMETER:g} and "
                    f"{MAX_PARAMETER:g}, got {data!r}",
                    path,
                )
        elif isinstance(data, Mapping):
            for key, value in data.items():
                self._sane_numbers(value, (*path, key))
        elif isinstance(data, list):
            for i, value in enumerate(data):
                self._sane_numbers(value, (*path, i))

    def traffic_lights(self, data: Any, path: KeyPath) -> TrafficLightsConfig:
        """``traffic_lights:`` -> :class:`TrafficLightsConfig` (see ``config/tls_yaml.py``)."""
        return parse_traffic_lights(self.loc, data, path)

    def _union(self, tp: Any, data: Any, path: KeyPath) -> Any:
        args = get_args(tp)
        if data is None and type(None) in args:
            return None
        options = [a for a in args if a is not type(None)]
        if len(options) == 1:
            return self.value(options[0], data, path)
        for option in options:
            if _fits(option, data):
                return self.value(option, data, path)
        raise self._expected(tp, data, path)

    def _scalar(self, tp: type, data: Any, path: KeyPath) -> Any:
        if isinstance(data, bool) and tp is not bool:
            raise self._expected(tp, data, path)
        if tp is float and isinstance(data, int | float):
            return float(data)
        if isinstance(data, tp):
            return data
        raise self._expected(tp, data, path)

    def _expected(self, tp: Any, data: Any, path: KeyPath) -> Exception:
        return self.loc.error(f"expected {_describe(tp)}, got {show(data)}", path)


def _fits(tp: Any, data: Any) -> bool:
    """Whether ``data`` has the basic shape of ``tp`` (to pick a member of a union)."""
    if isinstance(data, bool):
        return tp is bool
    if tp is float:
        return isinstance(data, int | float)
    if tp in (int, str):
        return isinstance(data, tp)
    origin = get_origin(tp)
    if origin is list:
        return isinstance(data, list)
    return isinstance(data, Mapping)
