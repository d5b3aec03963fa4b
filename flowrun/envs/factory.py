"""Build an environment from an :class:`ExperimentConfig` (or a YAML file), or from its name
alone with the experiment the env comes with (:func:`default_experiment`)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

from flowrun.config.model import ExperimentConfig
from flowrun.config.signal_control import network_programs
from flowrun.envs.base import Env, check_additional_params
from flowrun.envs.registry import resolve_env_class
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config, override_config
from flowrun.networks.base import Network
from flowrun.networks.registry import network_class


def make_network(cfg: ExperimentConfig) -> Network:
    """The network object of a config, with its traffic-light programs (the declared ones,
    or those of ``traffic_lights.controller``)."""
    search_dir = Path(cfg.source).resolve().parent if cfg.source else None
    cls = network_class(cfg.network.type, search_dir)
    tls = cfg.traffic_lights
    network = cls(cfg.name, cfg.vehicles, cfg.network.net_params, cfg.initial, tls.programs)
    if tls.controller is not None:
        lights = [n.id for n in network.spec.nodes if n.type == "traffic_light"]
        network.traffic_lights = network_programs(tls, lights)
    return network


def env_class(cfg: ExperimentConfig) -> type[Env]:
    """The config's environment class, checked against its ``env.additional_params``.

    An import-path class is also looked for next to the config file. Nothing is started.

    Raises:
        ConfigError: unknown class (with did-you-mean), failed import, or ``additional_params``
            keys that the class declares in ``ADDITIONAL_ENV_PARAMS`` but the config lacks.
    """
    search_dir = Path(cfg.source).resolve().parent if cfg.source else None
    try:
        cls: type[Env] = resolve_env_class(cfg.env.env_class, search_dir)
        missing = sorted(getattr(cls, "__abstractmethods__", ()))
        if missing:
            raise ConfigError(
                f"environment class {cls.__name__} does not implement {', '.join(missing)}; "
                "an Env subclass defines action_space, observation_space, _apply_rl_actions "
                "and get_state (see the README's 'Write your own environment')",
                path="env.class",
            )
        check_additional_params(cls, cfg.env)
    except ConfigError as err:
        if cfg.source and not err.location:
            raise ConfigError(err.message, err.path, cfg.source) from None
        raise
    return cls


def make_env(
    cfg: ExperimentConfig, render_mode: str | None = None, work_dir: Path | None = None
) -> Env:
    """Instantiate the config's environment class on its network (see :func:`env_class`)."""
    cls = env_class(cfg)
    network = make_network(cfg)
    return cls(cfg.env, cfg.sim, network, render_mode=render_mode, work_dir=work_dir)


#: The repository's experiment files, which the envs' ``DEFAULT_EXPERIMENT`` names.
CONFIGS_DIR = Path(__file__).resolve().parents[2] / "configs"


def default_experiment(env_name: str) -> ExperimentConfig:
    """The experiment a built-in env comes with (``gymnasium.make`` without a config).

    The file its class names in ``DEFAULT_EXPERIMENT`` (a path under :data:`CONFIGS_DIR`),
    with ``env.class`` set to ``env_name`` and the keys of the class's
    ``ADDITIONAL_ENV_PARAMS`` the file lacks filled in.

    Raises:
        ConfigError: the class names no file (give the env a config).
    """
    cls = resolve_env_class(env_name)
    file = getattr(cls, "DEFAULT_EXPERIMENT", None)
    if file is None:
        raise ConfigError(
            f"{env_name} names no DEFAULT_EXPERIMENT; give it a config "
            "(gymnasium.make(..., config='my.yaml'))"
        )
    cfg = load_config(CONFIGS_DIR / file)
    params = {**getattr(cls, "ADDITIONAL_ENV_PARAMS", {}), **cfg.env.additional_params}
    return replace(cfg, env=replace(cfg.env, env_class=env_name, additional_params=params))


def make_registered(
    env_name: str,
    config: str | Path | ExperimentConfig | None = None,
    overrides: list[str] | tuple[str, ...] = (),
    render_mode: str | None = None,
    **env_changes: Any,
) -> Env:
    """Gymnasium entry point: ``gymnasium.make("flowrun/<Name>-v0", ...)``.

    Args:
        env_name: the registered env.
        config: a YAML path or config; the env's own experiment when omitted
            (:func:`default_experiment`).
        overrides: ``a.b=value`` overrides, as ``--set`` on the command line.
        render_mode: ``None`` or ``"rgb_array"``.
        env_changes: ``EnvParams`` fields to replace, e.g. ``horizon=500``.
    """
    if isinstance(config, ExperimentConfig):
        cfg = config
    elif config is not None:
        cfg = load_config(Path(config), overrides)
        overrides = ()
    else:
        cfg = default_experiment(env_name)
    if overrides:
        cfg = override_config(cfg, list(overrides))
    env_params = replace(cfg.env, env_class=cfg.env.env_class or env_name, **env_changes)
    return make_env(replace(cfg, env=env_params), render_mode=render_mode)
