"""Load an experiment config: YAML file (+ ``--set`` overrides) -> validated ``ExperimentConfig``.

Checks run in this order and the first problem raises one :class:`ConfigError` carrying the
key path and ``file:line``: the file itself (a regular UTF-8 text file of at most 1 MiB, not
empty), YAML syntax, duplicate keys, size and nesting, then each section's keys, types and
values, then what spans sections (unique vehicle group ids, controller names and parameters,
inflow vehicle types, network-specific limits, and :mod:`flowrun.loading.experiment_checks`:
step length, the seeded initial placement, departure speeds, training values). Settings that
would have no effect are logged as warnings. The environment class is resolved when the
environment is made (loading sits below ``flowrun.envs`` and does not import it);
:mod:`flowrun.preflight.checks` (``flowrun validate``) resolves it too.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import re
import stat
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from flowrun.config.convert import Converter
from flowrun.config.model import ExperimentConfig
from flowrun.config.overrides import apply_overrides
from flowrun.config.params import VehicleType
from flowrun.config.yamlio import KeyPath, Locations, format_path, parse_yaml
from flowrun.controllers.registry import ControllerKind, build_controller, resolve_controller
from flowrun.errors import ConfigError, FlowrunError
from flowrun.import_path import import_near
from flowrun.loading.experiment_checks import check_experiment, ignored_settings, sub_path
from flowrun.networks.registry import network_class, validate_network
from flowrun.networks.routes import check_inflow_route
from flowrun.networks.tls import check_programs
from flowrun.suggest import did_you_mean

# Controller fields of a vehicle group and the controller kind each one takes.
_CONTROLLER_FIELDS: dict[str, ControllerKind] = {
    "acceleration_controller": "acceleration",
    "lane_change_controller": "lane_change",
    "routing_controller": "routing",
}
log = logging.getLogger(__name__)
_SECTIONS = "name, sim, env, network, vehicles, initial, traffic_lights, train"
#: Largest config file read (flowrun's own are ~2 kB).
MAX_CONFIG_BYTES = 1 << 20


def load_config(path: str | os.PathLike[str], overrides: Sequence[str] = ()) -> ExperimentConfig:
    """Read, override and validate one experiment config file.

    Args:
        path: the YAML file. Without a ``name:`` key the file's stem names the experiment.
        overrides: ``key.path=value`` strings (``sim.step=0.5``, ``vehicles[0].count=10``);
            each value is read as YAML. Later overrides win.

    Returns:
        The validated config.

    Raises:
        ConfigError: the first problem found, with its key path and ``file:line``.
    """
    return load_config_located(path, overrides)[0]


def load_config_located(
    path: str | os.PathLike[str], overrides: Sequence[str] = ()
) -> tuple[ExperimentConfig, Locations]:
    """:func:`load_config`, also returning where each key stands (for later checks' errors)."""
    file = Path(path)
    source = str(path)
    data, locations = parse_yaml(read_config_text(file, source), source)
    if data is None:
        raise ConfigError(
            "the config file is empty (or only comments); a config needs at least a network "
            "and vehicles (see configs/sugiyama.yaml)",
            "",
            source,
        )
    if not isinstance(data, dict):
        raise locations.error(
            f"expected a mapping with the sections {_SECTIONS}; got a {type(data).__name__}", ()
        )
    if "name" not in data:
        data = {"name": file.stem, **data}
    apply_overrides(data, overrides, locations)
    return dataclasses.replace(_build(data, locations), source=source), locations


def read_config_text(file: Path, source: str) -> str:
    """The text of a config file, or one :class:`ConfigError` saying why it cannot be one.

    Refused without reading: a missing path, a directory, anything but a regular file (a FIFO
    would block, a device never end) and a file over :data:`MAX_CONFIG_BYTES`. Refused after
    reading: bytes that are not UTF-8 (at the line of the first bad byte).
    """
    try:
        info = file.stat()
    except FileNotFoundError:
        raise ConfigError(
            f"config file not found (looked for {file.absolute()}); check the path", "", source
        ) from None
    except OSError as err:
        raise ConfigError(f"cannot read the config file: {err.strerror}", "", source) from None
    if stat.S_ISDIR(info.st_mode):
        raise ConfigError("is a directory; expected a YAML config file", "", source)
    if not stat.S_ISREG(info.st_mode):
        raise ConfigError(
            "is not a regular file (a FIFO, socket or device); expected a YAML config file",
            "",
            source,
        )
    if info.st_size > MAX_CONFIG_BYTES:
        raise ConfigError(
            f"is {info.st_size} bytes; a YAML config is a few kB (at most {MAX_CONFIG_BYTES}): "
            "is this the right file?",
            "",
            source,
        )
    try:
        raw = file.read_bytes()
    except OSError as err:
        raise ConfigError(f"cannot read the config file: {err.strerror}", "", source) from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = raw.count(b"\n", 0, err.start) + 1
        raise ConfigError(
            f"byte 0x{raw[err.start]:02x} is not UTF-8 text; save the config as UTF-8",
            "",
            f"{source}:{line}",
        ) from None


def config_from_dict(data: Mapping[str, Any], source: str = "<dict>") -> ExperimentConfig:
    """Validate plain data (a parsed YAML document) into an :class:`ExperimentConfig`.

    Args:
        data: mapping of sections, as in the YAML file.
        source: name used as the location of errors.

    Raises:
        ConfigError: the first problem found, with its key path.
    """
    locations = Locations(source)
    if not isinstance(data, Mapping):
        raise locations.error(f"expected a mapping with the sections {_SECTIONS}", ())
    return _build(dict(data), locations)


def _build(data: dict[str, Any], loc: Locations) -> ExperimentConfig:
    cfg: ExperimentConfig = Converter(loc).section(ExperimentConfig, data, ())
    _check_group_ids(cfg, data, loc)
    _check_controllers(cfg, data, loc)
    if not data.get("network"):  # a default ring would run another experiment unnoticed
        raise loc.error(
            "the config has no network: section; give the road, e.g. "
            "network: {type: ring, length: 230} (flowrun list networks shows every type)",
            ("network",),
        )
    _check_network(cfg, loc)
    network = _build_network(cfg, loc)
    edges = [edge.id for edge in network.spec.edges]
    _check_inflows(cfg, edges, loc, network.vehicles.type_names)
    _check_inflow_routes(cfg, network, loc)
    _check_traffic_lights(cfg, network, loc)
    check_experiment(cfg, network, loc)
    for path, why in ignored_settings(cfg):
        log.warning("%s: %s %s", loc.of(path), format_path(path), why)
    return cfg


def _given_key(raw: Any, cls: type, field_name: str) -> str:
    """The spelling of a field used in ``raw`` (its YAML key or the field name)."""
    aliases = [k for k, v in getattr(cls, "YAML_KEYS", {}).items() if v == field_name]
    for key in (*aliases, field_name):
        if isinstance(raw, Mapping) and key in raw:
            return str(key)
    return aliases[0] if aliases else field_name


def _raw_group(data: Mapping[str, Any], i: int) -> Any:
    groups = data.get("vehicles")
    return groups[i] if isinstance(groups, list) and i < len(groups) else None


def _check_group_ids(cfg: ExperimentConfig, data: Mapping[str, Any], loc: Locations) -> None:
    first: dict[str, int] = {}
    for i, group in enumerate(cfg.vehicles.groups):
        if group.veh_id in first:
            key = _given_key(_raw_group(data, i), VehicleType, "veh_id")
            other = first[group.veh_id]
            raise loc.error(
                f"duplicate vehicle group id '{group.veh_id}' (also vehicles[{other}]);"
                " give each group its own id",
                ("vehicles", i, key),
            )
        first[group.veh_id] = i


def _check_controllers(cfg: ExperimentConfig, data: Mapping[str, Any], loc: Locations) -> None:
    for i, group in enumerate(cfg.vehicles.groups):
        raw = _raw_group(data, i)
        for name, kind in _CONTROLLER_FIELDS.items():
            spec = getattr(group, name)
            if spec is None:
                continue
            at: KeyPath = ("vehicles", i, name)
            given = raw.get(name) if isinstance(raw, Mapping) else None
            try:
                if ":" in spec.type:  # a user's module:Class, found beside the config too
                    module_name = spec.type.partition(":")[0]
                    if module_name:
                        import_near(module_name, spec.type, _search_dir(loc), "controller", "")
                resolve_controller(spec.type, kind)
            except ConfigError as err:
                type_at = (*at, "type") if isinstance(given, Mapping) else at
                raise loc.error(err.message, type_at) from None
            try:
                build_controller(spec.type, dict(spec.params), kind)
            except ConfigError as err:
                raise loc.error(err.message, (*at, *_param_path(err, spec.params))) from None


def _param_path(err: ConfigError, params: Mapping[str, Any]) -> KeyPath:
    """The parameter a controller's error is about: its ``path``, else the first one it names."""
    if err.path:
        return sub_path(err.path)
    for pattern in ("'{}'", r"\b{}\b"):
        found = [
            (m.start(), key)
            for key in params
            if (m := re.search(pattern.format(re.escape(str(key))), err.message))
        ]
        if found:
            return (min(found)[1],)
    return ()


def _check_inflows(
    cfg: ExperimentConfig, edges: list[str] | None, loc: Locations, types: list[str] | None
) -> None:
    """Each inflow's type and edge exist; ``types``: the network's vehicle types (the groups
    and a template's vTypes), the groups when the network could not be built."""
    inflows = cfg.network.net_params.inflows
    if inflows is None:
        return
    types = cfg.vehicles.type_names if types is None else types
    for j, flow in enumerate(inflows.get()):
        if flow.veh_type not in types:
            raise loc.error(
                f"no vehicle group '{flow.veh_type}'{did_you_mean(flow.veh_type, types)}; "
                "inflows use the id of a group under vehicles (or of a vType of a template's "
                f"vtype file): {', '.join(types) or '(none)'}",
                ("network", "inflows", j, "veh_type"),
            )
    for j, flow in enumerate(inflows.get()):
        if edges is not None and flow.edge not in edges:
            raise loc.error(
                f"no edge '{flow.edge}' in the {cfg.network.type} network"
                f"{did_you_mean(flow.edge, edges)}; its edges are: {', '.join(edges)}",
                ("network", "inflows", j, "edge"),
            )


def _check_inflow_routes(cfg: ExperimentConfig, network: Any, loc: Locations) -> None:
    """An inflow's ``route`` names one of the network's routes, starting on its edge."""
    inflows = cfg.network.net_params.inflows
    if inflows is None:
        return
    for j, flow in enumerate(inflows.get()):
        if flow.route is None:
            continue
        try:
            check_inflow_route(network.spec, flow.route, flow.edge)
        except ConfigError as err:
            raise loc.error(err.message, ("network", "inflows", j, "route")) from None


def _build_network(cfg: ExperimentConfig, loc: Locations) -> Any:
    """Build the config's network (its road, not SUMO's files).

    A network that cannot be built (a missing template file, a route over unconnected
    edges, ...) is reported at its key.
    """
    try:
        cls = network_class(cfg.network.type, _search_dir(loc))
        tls = cfg.traffic_lights.programs  # a network may make the nodes with lights ones
        network = cls(cfg.name, cfg.vehicles, cfg.network.net_params, cfg.initial, tls)
    except ConfigError as err:
        message = f"{err.location}: {err.message}" if err.location else err.message
        raise loc.error(message, ("network", *sub_path(err.path))) from None
    except FlowrunError as err:  # e.g. netconvert refusing an OpenStreetMap file
        raise loc.error(str(err), ("network",)) from None
    return network


def _check_traffic_lights(cfg: ExperimentConfig, network: Any, loc: Locations) -> None:
    """Declared programs against the junctions netconvert builds (one character per link);
    a controller on a network with lights."""
    tls = cfg.traffic_lights
    at: KeyPath = ("traffic_lights",)
    no_lights = not any(n.type == "traffic_light" for n in network.spec.nodes)
    if tls.controller is not None and network.spec.net_file is None and no_lights:
        raise loc.error(
            f"controller {tls.controller} switches traffic lights, but the "
            f"{cfg.network.type} network has none (give a node type 'traffic_light' or "
            "add one under traffic_lights.lights)",
            (*at, "controller"),
        )
    params = tls.programs
    if not (params.get_properties() or params.baseline):
        return
    try:
        check_programs(network, params)
    except ConfigError as err:
        declared = list(params.get_properties())
        node = next((n for n in declared if err.path.startswith(f"traffic_lights.{n}")), None)
        if node is None:  # the actuated default of ``baseline: true``
            raise loc.error(f"baseline program: {err.message}", (*at, "baseline")) from None
        from flowrun.config.tls_yaml import light_subpath

        sub = light_subpath(err.path, node)
        raise loc.error(err.message, (*at, "lights", declared.index(node), *sub)) from None
    except FlowrunError as err:
        raise loc.error(str(err), ("network",)) from None


def _search_dir(loc: Locations) -> Path | None:
    """The config file's folder: where a user's ``module:Class`` is also looked for."""
    file = Path(loc.source)
    return file.resolve().parent if file.is_file() else None


def _check_network(cfg: ExperimentConfig, loc: Locations) -> None:
    params = dict(cfg.network.net_params.additional_params)
    try:
        validate_network(cfg.network.type, params, cfg.vehicles, cfg.initial, _search_dir(loc))
    except ConfigError as err:
        raise loc.error(err.message, ("network", *sub_path(err.path))) from None


def override_config(cfg: ExperimentConfig, overrides: Sequence[str]) -> ExperimentConfig:
    """``cfg`` with ``key.path=value`` overrides applied and validated again."""
    from flowrun.config.dump import config_to_dict

    data = config_to_dict(cfg)
    locations = Locations(f"<config {cfg.name}>")
    apply_overrides(data, overrides, locations)
    return dataclasses.replace(_build(data, locations), source=cfg.source)
