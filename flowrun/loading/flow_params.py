"""Flow's ``flow_params`` dict -> :class:`ExperimentConfig` (one way: the config is the model).

A Flow experiment config is a Python dict::

    flow_params = dict(exp_tag="ring", env_name=AccelEnv, network=RingNetwork, simulator="traci",
                       sim=SumoParams(...), env=EnvParams(...), net=NetParams(...),
                       veh=vehicles, initial=InitialConfig(...), tls=TrafficLightParams())

:func:`from_flow_params` turns it into the same :class:`ExperimentConfig` a YAML file gives
(validated by the same loader, so errors read alike) and keeps the class objects it was given
beside it: a user's env class defined in the config module is the class that runs.
:func:`load_flow_module` reads such a module from a ``.py`` file.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from flowrun.config.dump import config_to_dict
from flowrun.config.model import ExperimentConfig, NetworkConfig
from flowrun.config.params import (
    EnvParams,
    InitialConfig,
    NetParams,
    SumoParams,
    TrafficLightParams,
    VehicleParams,
)
from flowrun.config.signal_control import TrafficLightsConfig
from flowrun.errors import ConfigError
from flowrun.loading.loader import config_from_dict
from flowrun.suggest import did_you_mean

#: Keys of Flow's ``flow_params`` (``initial`` and ``tls`` may be left out).
FLOW_KEYS = ("exp_tag", "env_name", "network", "simulator", "sim", "env", "net", "veh")
OPTIONAL_KEYS = ("initial", "tls")
_TYPES: dict[str, type] = {
    "sim": SumoParams,
    "env": EnvParams,
    "net": NetParams,
    "veh": VehicleParams,
    "initial": InitialConfig,
    "tls": TrafficLightParams,
}
SIMULATORS = ("traci", "sumo", "libsumo")


@dataclass(frozen=True)
class FlowExperiment:
    """A ``flow_params`` dict as flowrun reads it.

    Attributes:
        config: the experiment as the YAML model (``env.class`` and ``network.type`` named).
        env_class: the environment class object when ``env_name`` was a class (else ``None``:
            the name in ``config.env.env_class`` is resolved when the env is made).
        network_class: the network class object when ``network`` was a class.
        traffic_lights: ``tls`` (also ``config.traffic_lights.programs``).
        simulator: ``simulator`` as given (SUMO in any case).
    """

    config: ExperimentConfig
    env_class: type | None = None
    network_class: type | None = None
    traffic_lights: TrafficLightParams | None = None
    simulator: str = "traci"


def class_path(cls: type) -> str:
    """``module:QualName``: how a config names a class that is not built in."""
    return f"{cls.__module__}:{cls.__qualname__}"


def _env_name(value: Any, where: str) -> tuple[str, type | None]:
    if isinstance(value, str):
        if not value:
            raise ConfigError("must name an environment class", "env_name", where)
        return value, None
    if not isinstance(value, type):
        raise ConfigError(
            f"expected an environment class or its name, got {value!r}", "env_name", where
        )
    # flowrun's own envs by name (loading does not import flowrun.envs); others by import path
    own = value.__module__.startswith("flowrun.envs.")
    return (value.__name__ if own else class_path(value)), value


def _network_type(value: Any, where: str) -> tuple[str, type | None]:
    """``network.type`` of a network class or name, and the class object if one was given."""
    from flowrun.networks.base import Network
    from flowrun.networks.registry import NETWORKS, network_class

    canonical = {cls: name for name, cls in NETWORKS.items()}
    if isinstance(value, type):
        if value in canonical:
            return canonical[value], value
        if value.__module__.startswith(("flowrun.networks", "flowrun.scenarios")):
            value = value.__name__  # e.g. the base ``Network`` (with a template)
        elif issubclass(value, Network):  # a user's network: by its import path
            return class_path(value), value
        else:
            raise ConfigError(
                f"{value.__qualname__} is not a network class: a network subclasses "
                "flowrun.networks.Network (Flow's Network) or is one of flowrun's "
                f"({', '.join(c.__name__ for c in NETWORKS.values())})",
                "network",
                where,
            )
    if not isinstance(value, str):
        raise ConfigError(f"expected a network class or its name, got {value!r}", "network", where)
    by_class = {cls.__name__: name for name, cls in NETWORKS.items()}
    if value in by_class:
        return by_class[value], None
    try:
        return canonical.get(network_class(value), value), None
    except ConfigError:
        names = [*by_class, *NETWORKS]
        raise ConfigError(
            f"unknown network '{value}'{did_you_mean(value, names)}; "
            f"expected a class or one of: {', '.join(names)}",
            "network",
            where,
        ) from None


def _section(params: Mapping[str, Any], key: str, where: str) -> Any:
    value = params.get(key)
    if value is None and key in OPTIONAL_KEYS:
        return _TYPES[key]()
    cls = _TYPES[key]
    if not isinstance(value, cls):
        raise ConfigError(
            f"expected a {cls.__name__} (from flowrun.core.params), got {type(value).__name__}",
            key,
            where,
        )
    return copy.deepcopy(value)


def from_flow_params(params: Mapping[str, Any], source: str | None = None) -> FlowExperiment:
    """Read Flow's ``flow_params`` dict.

    Args:
        params: the dict (``exp_tag, env_name, network, simulator, sim, env, net, veh``;
            optionally ``initial`` and ``tls``). ``env_name`` and ``network`` are classes or
            their names.
        source: the file it came from (named in errors; an import-path env class is also
            looked for next to it).

    Raises:
        ConfigError: a missing or unknown key, a value of the wrong kind, or anything the
            YAML loader would refuse (same checks, same messages).
    """
    where = f"{source} (flow_params)" if source else "flow_params"
    if not isinstance(params, Mapping):
        raise ConfigError(f"expected a dict, got {type(params).__name__}", "", where)
    known = (*FLOW_KEYS, *OPTIONAL_KEYS)
    for key in params:
        if key not in known:
            raise ConfigError(
                f"unknown key{did_you_mean(str(key), known)}; expected: {', '.join(known)}",
                str(key),
                where,
            )
    missing = [k for k in FLOW_KEYS if k not in params and k != "simulator"]
    if missing:
        raise ConfigError(f"missing key(s) {', '.join(missing)}", "", where)
    tag = params["exp_tag"]
    if not isinstance(tag, str) or not tag:
        raise ConfigError(f"expected the experiment's name, got {tag!r}", "exp_tag", where)
    simulator = params.get("simulator", "traci")
    if simulator not in SIMULATORS:
        raise ConfigError(
            f"flowrun runs SUMO only; use simulator='traci', got {simulator!r}",
            "simulator",
            where,
        )
    env_name, env_cls = _env_name(params["env_name"], where)
    net_type, net_cls = _network_type(params["network"], where)
    env: EnvParams = _section(params, "env", where)
    tls: TrafficLightParams = _section(params, "tls", where)
    cfg = ExperimentConfig(
        name=tag,
        sim=_section(params, "sim", where),
        env=dataclasses.replace(env, env_class=env_name),
        network=NetworkConfig(net_type, _section(params, "net", where)),
        vehicles=_section(params, "veh", where),
        initial=_section(params, "initial", where),
        traffic_lights=TrafficLightsConfig(tls),
    )
    # Through the YAML layout and the loader: one model, one set of checks.
    checked = config_from_dict(config_to_dict(cfg), source=where)
    return FlowExperiment(
        config=dataclasses.replace(checked, source=source),
        env_class=env_cls,
        network_class=net_cls,
        traffic_lights=checked.traffic_lights.programs,
        simulator=str(simulator),
    )


def config_from_flow_params(
    params: Mapping[str, Any], source: str | None = None
) -> ExperimentConfig:
    """The :class:`ExperimentConfig` of a ``flow_params`` dict (see :func:`from_flow_params`)."""
    return from_flow_params(params, source).config
