"""Checks across sections that need the built network (run by the loader, before any run).

Each one refuses a config that ``baseline``/``train`` would otherwise accept and then fail on
(or run wrongly), as one :class:`ConfigError` at the key path and ``file:line`` of the
setting to change:

- ``network.template`` / ``osm_path`` given to a network type that builds its own road;
- ``sim.step`` so long that a car passes a whole edge in one step (routes and leaders break);
- the initial placement (run once with the seed, as the first reset will): cars that do not
  fit, ``initial.min_gap`` that the spacing cannot leave, unknown edges;
- an ``initial_speed`` SUMO refuses (above the vehicle type's ``max_speed`` or the speed
  limit times ``speed_factor`` of the edge the car starts on);
- ``train.hyperparams`` values SB3 fails on (``batch_size: 0``, ``gamma: 2``, NaN).

:func:`ignored_settings` lists what is accepted but has no effect in a run (warnings).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from flowrun.config.hyperparams import check_hyperparam_values
from flowrun.config.model import ExperimentConfig
from flowrun.config.overrides import parse_key
from flowrun.config.params import SumoParams
from flowrun.config.yamlio import KeyPath, Locations
from flowrun.errors import ConfigError


def sub_path(path: str) -> KeyPath:
    """A path reported by another module's ConfigError, as key-path parts."""
    if not path:
        return ()
    try:
        return parse_key(path)
    except ConfigError:
        return (path,)


def check_experiment(cfg: ExperimentConfig, network: Any, loc: Locations) -> None:
    """Run the checks above on the config and its built ``network``.

    Raises:
        ConfigError: the first problem, located.
    """
    check_env_params(cfg.env.additional_params, {}, loc)
    _check_train_values(cfg, loc)
    _check_sublane(cfg, loc)
    _check_network_inputs(cfg, network, loc)
    _check_step(cfg, network, loc)
    _check_start(cfg, network, loc)
    _check_inflow_lanes(cfg, network, loc)


def _check_inflow_lanes(cfg: ExperimentConfig, network: Any, loc: Locations) -> None:
    """A lane index an inflow departs on exists on its edge (SUMO refuses it otherwise)."""
    lanes = {e.id: e.lanes for e in network.spec.edges}
    inflows = cfg.network.net_params.inflows
    for j, flow in enumerate(inflows.get() if inflows is not None else []):
        lane = flow.depart_lane
        if isinstance(lane, int) and flow.edge in lanes and lane >= lanes[flow.edge]:
            raise loc.error(
                f"edge '{flow.edge}' has {lanes[flow.edge]} lane(s), numbered from 0; "
                f"got lane {lane}",
                ("network", "inflows", j, "depart_lane"),
            )


#: Flow's environment parameters whose meaning is known whatever the env: must be > 0.
POSITIVE_ENV_PARAMS = ("max_accel", "max_decel", "target_velocity", "switch_time",
                       "lane_change_duration", "max_speed")  # fmt: skip
#: ... integers >= 0.
COUNT_ENV_PARAMS = ("num_rl", "num_observed", "num_local_edges", "num_local_lights")
#: Widest policy layer accepted in ``train.policy_kwargs.net_arch``.
MAX_LAYER = 100_000
#: Largest number an environment parameter may be (beyond it spaces and rewards overflow).
MAX_ENV_NUMBER = 1e9


def check_env_params(params: dict[str, Any], declared: dict[str, Any], loc: Locations) -> None:
    """Values of ``env.additional_params``: numbers finite and at most 1e9 in size (NaN or
    1e308 make gymnasium spaces and rewards fail), Flow's well-known keys in range
    (``max_accel > 0``, ``num_rl >= 0`` ...), and, where the env class ``declared`` a default
    (its ``ADDITIONAL_ENV_PARAMS``), a value of the same kind (a number for a number, a
    list of as many numbers for a list, true/false for a flag, text for text).

    Raises:
        ConfigError: at ``env.additional_params.<key>``.
    """
    base: KeyPath = ("env", "additional_params")
    for key, value in params.items():
        at = (*base, key)
        _finite_numbers(value, at, loc)
        if key in declared and declared[key] is not None:
            _same_kind(value, declared[key], at, loc)
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if key in POSITIVE_ENV_PARAMS and not (number and value > 0):
            raise loc.error(f"expected a number > 0, got {value!r}", at)
        if key in COUNT_ENV_PARAMS and (not isinstance(value, int) or isinstance(value, bool)
                                        or value < 0):  # fmt: skip
            raise loc.error(f"expected an integer >= 0, got {value!r}", at)
        if key == "ring_length" and value is not None:
            ok = isinstance(value, list) and len(value) == 2
            ok = ok and all(isinstance(x, int | float) and not isinstance(x, bool) for x in value)
            if not ok or not 0 < value[0] <= value[1]:
                raise loc.error(
                    f"expected [low, high] ring lengths in m with 0 < low <= high, got {value!r}",
                    at,
                )


def _finite_numbers(value: Any, at: KeyPath, loc: Locations) -> None:
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if number and not abs(value) <= MAX_ENV_NUMBER:  # NaN fails the comparison too
        raise loc.error(
            f"expected a finite number between -{MAX_ENV_NUMBER:g} and {MAX_ENV_NUMBER:g}, "
            f"got {value!r}",
            at,
        )
    if isinstance(value, dict):
        for key, item in value.items():
            _finite_numbers(item, (*at, key), loc)
    elif isinstance(value, list):
        for i, item in enumerate(value):
            _finite_numbers(item, (*at, i), loc)


def _kind(x: Any) -> str:
    if isinstance(x, bool):
        return "true or false"
    if isinstance(x, int | float):
        return "a number"
    if isinstance(x, str):
        return "text"
    if isinstance(x, list | tuple):
        return "a list"
    return "a mapping" if isinstance(x, dict) else type(x).__name__


def _same_kind(value: Any, default: Any, at: KeyPath, loc: Locations) -> None:
    """``value`` has the shape of the env's ``default``: same kind; a list of numbers as long
    (``[low, high]``); a list of like items, each shaped like them; a mapping's shared keys."""
    if value is None or default is None:
        return
    if _kind(value) != _kind(default):
        raise loc.error(f"expected {_kind(default)} (default {default!r}), got {value!r}", at)
    if isinstance(default, dict):
        for key in set(value) & set(default):
            _same_kind(value[key], default[key], (*at, key), loc)
    if not isinstance(default, list | tuple) or not default:
        return
    kinds = {_kind(d) for d in default}
    if kinds == {"a number"} and len(value) != len(default):
        raise loc.error(
            f"expected a list of {len(default)} numbers (default {list(default)!r}), "
            f"got {value!r}",
            at,
        )
    if len(kinds) == 1:
        for i, item in enumerate(value):
            _same_kind(item, default[0], (*at, i), loc)
    elif len(value) == len(default):  # a record such as ("1", 1, False)
        for i, (item, like) in enumerate(zip(value, default, strict=True)):
            _same_kind(item, like, (*at, i), loc)


def _check_sublane(cfg: ExperimentConfig, loc: Locations) -> None:
    """SUMO's sublane model (``sim.lateral_resolution``) refuses the LC2013 lane changer."""
    if cfg.sim.lateral_resolution is None:
        return
    for i, group in enumerate(cfg.vehicles.groups):
        if group.lane_change_params.model != "SL2015":
            raise loc.error(
                f"SUMO's sublane model needs the SL2015 lane-change model, but vehicles[{i}] "
                f"('{group.veh_id}') uses {group.lane_change_params.model}; set its "
                "lane_change: {model: SL2015}, or remove lateral_resolution",
                ("sim", "lateral_resolution"),
            )


def _check_network_inputs(cfg: ExperimentConfig, network: Any, loc: Locations) -> None:
    net = cfg.network.net_params
    if network.spec.net_file is not None:
        return  # a road read from a file: template / osm_path are what it is built from
    for key in ("template", "osm_path"):
        if getattr(net, key) is not None:
            raise loc.error(
                f"the {cfg.network.type} network builds its own road, so {key} would be "
                "ignored; use network type 'template' to read a road from a file, or remove "
                f"{key}",
                ("network", key),
            )


def _check_step(cfg: ExperimentConfig, network: Any, loc: Locations) -> None:
    edges = [e for e in network.spec.edges if not e.id.startswith(":")]
    if not edges:
        return
    shortest = min(edges, key=lambda e: e.length)
    factor = max((g.car_following_params.speed_factor for g in cfg.vehicles.groups), default=1.0)
    top = max((g.car_following_params.max_speed for g in cfg.vehicles.groups), default=np.inf)
    speed = min(max(e.speed for e in edges) * factor, top)
    step = cfg.sim.sim_step
    if speed * step > shortest.length:
        raise loc.error(
            f"a car at {speed:g} m/s passes {speed * step:g} m in a step of {step:g} s, more than "
            f"the shortest edge ('{shortest.id}', {shortest.length:g} m): SUMO's routing and "
            f"the leaders need every car to enter each edge it passes; use a step of at most "
            f"{shortest.length / speed:.2g} s",
            ("sim", "step"),
        )


def _check_start(cfg: ExperimentConfig, network: Any, loc: Locations) -> None:
    """Place the cars as the first reset will (same seed) and check their entry speeds."""
    rng = np.random.default_rng(int(cfg.sim.seed or 0))
    try:
        start = network.start_positions(rng)
    except ConfigError as err:
        at = sub_path(err.path)
        section = "network" if at and at[0] in ("length", "lanes") else "initial"
        raise loc.error(err.message, (section, *at)) from None
    speed_limit = {e.id: e.speed for e in network.spec.edges}
    groups = [(i, g) for i, g in enumerate(cfg.vehicles.groups) for _ in range(g.num_vehicles)]
    for (i, group), edge in zip(groups, start.edges, strict=False):
        v0 = group.initial_speed
        cf = group.car_following_params
        limit = speed_limit.get(edge, np.inf) * cf.speed_factor
        if v0 > cf.max_speed or v0 > limit:
            raise loc.error(
                f"SUMO refuses to insert a car at {v0:g} m/s here: above the vehicle type's "
                f"max_speed ({cf.max_speed:g} m/s) or edge '{edge}''s speed limit times "
                f"speed_factor ({limit:g} m/s); use at most {min(cf.max_speed, limit):g}",
                ("vehicles", i, "initial_speed"),
            )


def _check_train_values(cfg: ExperimentConfig, loc: Locations) -> None:
    train = cfg.train
    if train is None:
        return
    for f in dataclasses.fields(train):  # hyperparams, policy_kwargs, the backends' own
        value = getattr(train, f.name)
        if isinstance(value, dict):
            _finite_numbers(value, ("train", f.name), loc)
    log_std = train.policy_kwargs.get("log_std_init")
    if log_std is not None and (isinstance(log_std, bool) or not isinstance(log_std, int | float)):
        raise loc.error(
            f"expected a number, got {log_std!r}", ("train", "policy_kwargs", "log_std_init")
        )
    arch = train.policy_kwargs.get("net_arch")
    layers = list(arch.values()) if isinstance(arch, dict) else [arch]
    for layer in layers:
        if layer is None:
            continue
        sizes = layer if isinstance(layer, list) else [layer]
        if not all(isinstance(n, int) and not isinstance(n, bool) and 1 <= n <= MAX_LAYER
                   for n in sizes):  # fmt: skip
            raise loc.error(
                f"expected layer sizes (integers 1 to {MAX_LAYER}) as [64, 64] or "
                f"{{pi: [64], vf: [64]}}, got {arch!r}",
                ("train", "policy_kwargs", "net_arch"),
            )
    if train.backend != "sb3" or not train.hyperparams:
        return
    try:
        check_hyperparam_values(train.algorithm, train.hyperparams, train.n_envs)
    except ConfigError as err:
        raise loc.error(err.message, sub_path(err.path)) from None


#: ``sim`` settings Flow has that flowrun stores (so Flow code can read them) but never uses.
STORED_ONLY = {
    "port": "is Flow's TraCI port; flowrun runs SUMO in-process (libsumo) and ignores it",
    "num_clients": "is Flow's number of TraCI clients; flowrun ignores it",
    "use_libsumo": "is Flow's switch to libsumo; flowrun always runs libsumo and ignores it",
    "save_render": "is for Flow's pyglet renderer, which flowrun does not have "
    "(baseline --render writes a GIF)",
    "show_radius": "is for Flow's pyglet renderer, which flowrun does not have",
    "force_color_update": "is Flow's sumo-gui colouring switch; flowrun ignores it",
    "color_by_speed": "is Flow's sumo-gui colouring switch; flowrun ignores it",
    "disable_collisions": "is ignored: flowrun always counts collisions (and ends the "
    "episode on one)",
}


def ignored_settings(cfg: ExperimentConfig) -> list[tuple[KeyPath, str]]:
    """Settings a config may hold that change nothing in a ``baseline``/``train`` run.

    Returns:
        ``(key path, why)`` pairs, for warnings.
    """
    out: list[tuple[KeyPath, str]] = []
    if cfg.sim.emission_path is not None:
        out.append((
            ("sim", "emission_path"),
            "is used only by Experiment.run(convert_to_csv=True) in Python; flowrun baseline "
            "and train log to MCAP in the run folder (flowrun replay --csv exports CSV)",
        ))  # fmt: skip
    defaults = SumoParams()
    for name, why in STORED_ONLY.items():
        if getattr(cfg.sim, name) != getattr(defaults, name):
            out.append((("sim", name), why))
    if cfg.vehicles.num_vehicles == 0 and not cfg.network.net_params.inflows.get():  # type: ignore[union-attr]
        template = cfg.network.net_params.template
        if not (isinstance(template, dict) and template.get("rou")):
            out.append((
                ("vehicles",),
                "no vehicles and no inflows: a run has nothing to drive or measure",
            ))  # fmt: skip
    return out
