"""``ExperimentConfig`` -> plain data -> YAML: the inverse of :mod:`flowrun.loading.loader`.

Every field is written (the resolved config), under its YAML key, so a dumped file states the
whole experiment and loads back to an equal config. YAML has no tuples: a tuple inside a free
``additional_params`` dict is written as a list.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import Any

from flowrun.config.convert import NETWORK_KEYS, yaml_key
from flowrun.config.model import ExperimentConfig, NetworkConfig
from flowrun.config.modes import LANE_CHANGE_MODES, SPEED_MODES, mode_name
from flowrun.config.params import (
    ControllerSpec,
    InFlows,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    VehicleParams,
)
from flowrun.config.signal_control import TrafficLightsConfig
from flowrun.config.tls_yaml import traffic_lights_data
from flowrun.config.yamlio import dump_yaml

# Mode fields are stored as SUMO's ints; the YAML says the name where the int has one.
_MODE_NAMES = {
    (SumoCarFollowingParams, "speed_mode"): SPEED_MODES,
    (SumoLaneChangeParams, "lane_change_mode"): LANE_CHANGE_MODES,
}


def config_to_dict(cfg: ExperimentConfig) -> dict[str, Any]:
    """The config as plain data in the YAML layout (``config_from_dict`` inverts it).

    ``train`` is left out when it is ``None`` (a config without training), ``traffic_lights``
    when nothing is declared (the network's own programs).
    """
    out = _section(cfg)
    if out.get("train") is None:
        out.pop("train", None)
    if cfg.traffic_lights.is_default:
        out.pop("traffic_lights", None)
    return out


def dump_config(cfg: ExperimentConfig) -> str:
    """The config as YAML text (``load_config`` of that text gives an equal config)."""
    return dump_yaml(config_to_dict(cfg))


def _section(obj: Any) -> dict[str, Any]:
    out = {}
    for f in dataclasses.fields(obj):
        if not f.metadata.get("yaml", True):
            continue
        value = getattr(obj, f.name)
        names = _MODE_NAMES.get((type(obj), f.name))
        out[yaml_key(type(obj), f.name)] = mode_name(value, names) if names else _plain(value)
    return out


def yaml_data(value: Any) -> Any:
    """Any parameter object (or section of one) as the plain data its YAML holds."""
    return _plain(value)


def _plain(value: Any) -> Any:
    if isinstance(value, ControllerSpec):
        return {"type": value.type, **copy.deepcopy(value.params)}
    if isinstance(value, VehicleParams):
        return [_section(group) for group in value.groups]
    if isinstance(value, InFlows):
        return [_section(flow) for flow in value.get()]
    if isinstance(value, NetworkConfig):
        return _network(value)
    if isinstance(value, TrafficLightsConfig):
        return traffic_lights_data(value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _section(value)
    if isinstance(value, dict | list | tuple):
        return copy.deepcopy(value)
    return value


def _network(net: NetworkConfig) -> dict[str, Any]:
    """``NetworkConfig`` -> ``{type: ring, length: 230, ...}`` (parameters flattened)."""
    params = net.net_params
    clash = sorted(set(params.additional_params) & set(NETWORK_KEYS))
    if clash:
        raise ValueError(f"network additional_params may not use the reserved keys {clash}")
    out: dict[str, Any] = {"type": net.type, **copy.deepcopy(params.additional_params)}
    if params.inflows is not None and params.inflows.num_flows:
        out["inflows"] = _plain(params.inflows)
    if params.template is not None:
        out["template"] = copy.deepcopy(params.template)
    if params.osm_path is not None:
        out["osm_path"] = params.osm_path
    return out
