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

import importlib
from collections.abc import Callable
from typing import Any

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.config.overrides import parse_key
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


def optional(module: str, attr: str) -> Callable[..., Any] | None:
    """``module.attr``, or ``None`` while that module is not written (or not installed)."""
    try:
        mod = importlib.import_module(module)
    except ModuleNotFoundError as err:
        if err.name and module.startswith(err.name):
            return None
        raise
    found = getattr(mod, attr, None)
    return found if callable(found) else None


def check_experiment(cfg: ExperimentConfig, network: Any, loc: Locations) -> None:
    """Run the checks above (``network`` is ``None`` while networks are not importable).

    Raises:
        ConfigError: the first problem, located.
    """
    _check_train_values(cfg, loc)
    if network is None:
        return
    _check_network_inputs(cfg, network, loc)
    _check_step(cfg, network, loc)
    _check_start(cfg, network, loc)


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
    if train is None or train.backend != "sb3" or not train.hyperparams:
        return
    check = optional("flowrun.training.algorithms", "check_hyperparam_values")
    if check is None:
        return
    try:
        check(train.algorithm, train.hyperparams, train.n_envs)
    except ConfigError as err:
        raise loc.error(err.message, sub_path(err.path)) from None


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
    if cfg.vehicles.num_vehicles == 0 and not cfg.network.net_params.inflows.get():  # type: ignore[union-attr]
        template = cfg.network.net_params.template
        if not (isinstance(template, dict) and template.get("rou")):
            out.append((
                ("vehicles",),
                "no vehicles and no inflows: a run has nothing to drive or measure",
            ))  # fmt: skip
    return out
