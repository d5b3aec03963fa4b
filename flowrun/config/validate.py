"""Check parameter objects built in Python with the rules the YAML loader applies.

The parameter classes are mutable, as in Flow (``sim_params.sim_step = 0.2``), so a value can
change after construction; :func:`check_params` checks the objects where they are used (an
environment being made, a ``flow_params`` dict being read). Same checks, same messages as
for a YAML file (``sim.sim_step: must be greater than 0, got -1``).
"""

from __future__ import annotations

from typing import Any

from flowrun.config.convert import Converter
from flowrun.config.dump import yaml_data
from flowrun.config.params import (
    EnvParams,
    InitialConfig,
    NetParams,
    SumoParams,
    VehicleParams,
)
from flowrun.config.yamlio import Locations

#: The YAML section each parameter class stands for (named in error paths).
SECTIONS: dict[type, str] = {
    SumoParams: "sim",
    EnvParams: "env",
    NetParams: "net",
    InitialConfig: "initial",
    VehicleParams: "vehicles",
}


def check_params(*objects: Any, where: str = "<python>") -> None:
    """Check each of ``objects`` (``SumoParams``, ``EnvParams``, ``NetParams``,
    ``InitialConfig``, ``VehicleParams``; anything else is skipped).

    Raises:
        ConfigError: the first impossible value, with its key path (``env.horizon``).
    """
    convert = Converter(Locations(where))
    for obj in objects:
        section = SECTIONS.get(type(obj))
        if section is None:
            continue
        if isinstance(obj, VehicleParams):
            convert.vehicles(yaml_data(obj), (section,))
        elif isinstance(obj, NetParams):
            _check_net(convert, obj, section)
        else:
            convert.section(type(obj), yaml_data(obj), (section,))


def _check_net(convert: Converter, net: NetParams, section: str) -> None:
    """The typed parts of ``NetParams`` (its ``additional_params`` are the network's to check)."""
    data = {
        "template": net.template,
        "osm_path": net.osm_path,
        "inflows": yaml_data(net.inflows) if net.inflows is not None else [],
    }
    convert.network({"type": "<any>", **data}, (section,))
