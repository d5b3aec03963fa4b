"""Network types by name (``network.type`` in a config)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from flowrun.config.params import InitialConfig, VehicleParams
from flowrun.errors import ConfigError
from flowrun.import_path import class_at, import_near
from flowrun.networks.base import Network
from flowrun.networks.bottleneck import BottleneckNetwork
from flowrun.networks.figure_eight import FigureEightNetwork
from flowrun.networks.highway import HighwayNetwork
from flowrun.networks.highway_ramps import HighwayRampsNetwork
from flowrun.networks.i210_subnetwork import I210SubNetwork
from flowrun.networks.merge import MergeNetwork
from flowrun.networks.minicity import MiniCityNetwork
from flowrun.networks.multi_ring import MultiRingNetwork
from flowrun.networks.ring import RingNetwork, check_ring_fits
from flowrun.networks.template import TemplateNetwork
from flowrun.networks.traffic_light_grid import TrafficLightGridNetwork
from flowrun.suggest import did_you_mean, unknown_name

NETWORKS: dict[str, type[Network]] = {
    "ring": RingNetwork,
    "figure_eight": FigureEightNetwork,
    "merge": MergeNetwork,
    "highway": HighwayNetwork,
    "template": TemplateNetwork,
    "traffic_light_grid": TrafficLightGridNetwork,
    "bottleneck": BottleneckNetwork,
    "highway_ramps": HighwayRampsNetwork,
    "i210_subnetwork": I210SubNetwork,
    "minicity": MiniCityNetwork,
    "multi_ring": MultiRingNetwork,
}
_ALIASES = {
    "loop": "ring",
    "RingNetwork": "ring",
    "LoopScenario": "ring",
    "figure8": "figure_eight",
    "FigureEightNetwork": "figure_eight",
    "FigureEightScenario": "figure_eight",
    "Figure8Scenario": "figure_eight",
    "MergeNetwork": "merge",
    "MergeScenario": "merge",
    "HighwayNetwork": "highway",
    "HighwayScenario": "highway",
    "TemplateNetwork": "template",
    "Network": "template",
    "grid": "traffic_light_grid",
    "TrafficLightGridNetwork": "traffic_light_grid",
    "TrafficLightGridScenario": "traffic_light_grid",
    "SimpleGridScenario": "traffic_light_grid",
    "BottleneckNetwork": "bottleneck",
    "BottleneckScenario": "bottleneck",
    "HighwayRampsNetwork": "highway_ramps",
    "HighwayRampsScenario": "highway_ramps",
    "I210SubNetwork": "i210_subnetwork",
    "MiniCityNetwork": "minicity",
    "MiniCityScenario": "minicity",
    "MultiRingNetwork": "multi_ring",
    "MultiRingScenario": "multi_ring",
    "MultiLoopScenario": "multi_ring",
}


def network_names() -> list[str]:
    """Names a config may use as ``network.type``."""
    return sorted(NETWORKS)


def network_class(name: str, search_dir: str | Path | None = None) -> type[Network]:
    """The network class registered as ``name`` (or one of its Flow class names), or a
    user's subclass of :class:`Network` named by its import path ``package.module:Class``.

    Args:
        name: a network type, a Flow class name, or ``package.module:Class``.
        search_dir: where else to look for the user's module (the config file's folder).

    Raises:
        ConfigError: unknown name (with did-you-mean), a failed import, or a class that is
            not a ``Network``.
    """
    if ":" in name:
        return _user_network(name, None if search_dir is None else Path(search_dir))
    key = _ALIASES.get(name, name)
    if key not in NETWORKS:
        raise ConfigError(
            unknown_name("network type", name, NETWORKS)
            + ", or a Network subclass's import path 'package.module:Class'",
            path="type",
        )
    return NETWORKS[key]


def _user_network(name: str, search_dir: Path | None) -> type[Network]:
    module_name, _, qualname = name.partition(":")
    if "<locals>" in qualname:
        raise ConfigError(
            f"network class '{name}' is defined inside a function, so it cannot be imported "
            "by name; define it at the top level of its module",
            path="type",
        )
    module = import_near(module_name, name, search_dir, "network", "type")
    cls = class_at(module, qualname)
    if cls is None:
        own = [
            n for n, v in vars(module).items()
            if isinstance(v, type) and issubclass(v, Network) and v.__module__ == module.__name__
        ]  # fmt: skip
        listed = f"; it defines {', '.join(sorted(own))}" if own else ""
        raise ConfigError(
            f"module '{module_name}' has no class '{qualname}'"
            f"{did_you_mean(qualname, own or dir(module))}{listed}",
            path="type",
        )
    if not (isinstance(cls, type) and issubclass(cls, Network)):
        raise ConfigError(
            f"'{name}' is not a subclass of flowrun.networks.Network (Flow's "
            "flow.networks.Network); a network class implements specify_nodes, "
            "specify_edges and specify_routes",
            path="type",
        )
    return cls


def network_table() -> list[tuple[str, str, dict[str, Any]]]:
    """``(name, Flow class name, parameter defaults)`` of every network type, by name."""
    return [
        (name, NETWORKS[name].__name__, dict(NETWORKS[name].ADDITIONAL_NET_PARAMS))
        for name in network_names()
    ]


def network_lines() -> list[str]:
    """``flowrun list networks``: one line per type: name, Flow class, parameters = defaults."""
    rows = network_table()
    width = max(len(name) for name, _, _ in rows)
    cls_width = max(len(cls) for _, cls, _ in rows)
    lines = []
    for name, cls, params in rows:
        note = getattr(NETWORKS[name], "LIST_NOTE", "")
        values = " ".join(f"{key}={_yaml_scalar(value)}" for key, value in params.items())
        lines.append(
            f"{name:<{width}}  {cls:<{cls_width}}  {values}" + (f"  ({note})" if note else "")
        )
    return lines


def _yaml_scalar(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def validate_network(
    network_type: str,
    params: dict[str, Any],
    vehicles: VehicleParams,
    initial: InitialConfig,
    search_dir: str | Path | None = None,
) -> None:
    """Check a network section before anything is built.

    Raises:
        ConfigError: with ``path`` relative to the network section (``type``, ``length``, ...).
    """
    cls = network_class(network_type, search_dir)
    resolved = cls.resolve_params(params)
    if cls is RingNetwork:
        check_ring_fits(resolved, vehicles, initial)
