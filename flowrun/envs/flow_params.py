"""Environments from a Flow ``flow_params`` dict (Flow's ``flow.utils.registry``).

``make_create_env(flow_params)`` returns ``(create_env, env_name)`` as in Flow: ``create_env()``
builds a fresh environment, and ``env_name`` (``<EnvClass>-v<version>``, the first version not
yet taken) is registered with Gymnasium, so ``gymnasium.make(env_name)`` works too. Both go
through :func:`flowrun.loading.flow_params.from_flow_params`: the env runs exactly the
:class:`~flowrun.config.model.ExperimentConfig` that ``flowrun convert`` would print.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import gymnasium

from flowrun.envs.base import Env
from flowrun.envs.factory import env_class, make_network
from flowrun.loading.flow_params import FlowExperiment, from_flow_params
from flowrun.networks.base import Network


def flow_network(flow: FlowExperiment) -> Network:
    """The network of a ``flow_params`` experiment (its own class object when it gave one)."""
    cfg = flow.config
    if flow.network_class is None:
        return make_network(cfg)
    network: Network = flow.network_class(
        cfg.name,
        copy.deepcopy(cfg.vehicles),
        cfg.network.net_params,
        cfg.initial,
        flow.traffic_lights,
    )
    return network


def make_flow_env(
    flow: FlowExperiment,
    render: bool | str | None = None,
    evaluate: bool = False,
    render_mode: str | None = None,
    work_dir: Path | None = None,
) -> Env:
    """Instantiate the environment of a ``flow_params`` experiment.

    Args:
        flow: the read ``flow_params``.
        render: overrides ``sim.render`` when true or a frame mode such as ``"drgb"`` (Flow's
            ``render or sim_params.render``).
        evaluate: sets ``EnvParams.evaluate`` (Flow's ``env_constructor(evaluate=True)``).
        render_mode: Gymnasium's ``render_mode`` (``None`` or ``"rgb_array"``).
        work_dir: folder for the generated SUMO files (a private temporary one by default).
    """
    cfg = flow.config
    cls = flow.env_class if flow.env_class is not None else env_class(cfg)
    sim = dataclasses.replace(cfg.sim, render=render or cfg.sim.render)  # or a mode
    env_params = dataclasses.replace(cfg.env, evaluate=True) if evaluate else cfg.env
    if flow.env_class is not None:  # the env gets the EnvParams as given (Flow's have no class)
        env_params = dataclasses.replace(env_params, env_class=None)
    env: Env = cls(
        env_params,
        sim,
        flow_network(flow),
        simulator=flow.simulator,
        render_mode=render_mode,
        work_dir=work_dir,
    )
    return env


def _base_name(params: Mapping[str, Any]) -> str:
    name = params.get("env_name")
    return name if isinstance(name, str) else getattr(name, "__name__", str(name))


def make_create_env(
    params: Mapping[str, Any], version: int = 0, render: bool | str | None = None
) -> tuple[Callable[..., Env], str]:
    """A creator of the ``flow_params`` environment and its Gymnasium id (Flow's signature).

    Args:
        params: Flow's ``flow_params`` dict.
        version: first version number to try; the id is ``<EnvClass>-v<n>`` for the first
            ``n >= version`` not registered yet.
        render: overrides ``sim.render`` when true.

    Returns:
        ``(create_env, env_name)``: ``create_env(*_)`` returns a new, not yet reset env.

    Raises:
        ConfigError: the ``flow_params`` are invalid (checked here, before any env exists).
    """
    flow = from_flow_params(params)
    base = _base_name(params)
    while f"{base}-v{version}" in gymnasium.registry:
        version += 1
    env_name = f"{base}-v{version}"

    def create_env(*_: Any, render_mode: str | None = None, **__: Any) -> Env:
        return make_flow_env(flow, render=render, render_mode=render_mode)

    gymnasium.register(id=env_name, entry_point=create_env, disable_env_checker=True)
    return create_env, env_name


def env_constructor(
    params: Mapping[str, Any],
    version: int = 0,
    render: bool | str | None = None,
    evaluate: bool = False,
) -> Callable[..., Env]:
    """A creator of the ``flow_params`` environment (Flow's ``env_constructor``).

    ``evaluate`` sets ``EnvParams.evaluate`` in the environments it creates.
    """
    if not evaluate:
        return make_create_env(params, version, render)[0]
    flow = from_flow_params(params)

    def create_env(*_: Any, render_mode: str | None = None, **__: Any) -> Env:
        return make_flow_env(flow, render=render, evaluate=True, render_mode=render_mode)

    return create_env
