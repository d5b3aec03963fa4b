"""Environment classes by name, user classes by import path, and Gymnasium registration."""

from __future__ import annotations

import importlib
from typing import Any

import gymnasium

from flowrun.errors import ConfigError
from flowrun.suggest import did_you_mean, unknown_name


def _builtin() -> dict[str, type]:
    from flowrun.envs.ring.accel import AccelEnv
    from flowrun.envs.ring.lane_change import LaneChangeAccelEnv
    from flowrun.envs.ring.wave_attenuation import WaveAttenuationEnv, WaveAttenuationPOEnv

    return {
        c.__name__: c
        for c in (AccelEnv, WaveAttenuationEnv, WaveAttenuationPOEnv, LaneChangeAccelEnv)
    }


def env_names() -> list[str]:
    """Names a config may use as ``env.class``."""
    return sorted(_builtin())


def resolve_env_class(name: str | None) -> type:
    """The environment class for a built-in name or an import path ``package.module:Class``.

    Raises:
        ConfigError: unknown name or failed import (with did-you-mean).
    """
    from flowrun.envs.base import Env

    if name is None:
        name = "AccelEnv"
    builtin = _builtin()
    if ":" not in name:
        if name not in builtin:
            raise ConfigError(
                unknown_name("environment", name, builtin)
                + ", or an import path 'package.module:Class'",
                path="env.class",
            )
        return builtin[name]
    module_name, _, attr = name.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as err:
        raise ConfigError(
            f"cannot import module '{module_name}' for environment '{name}': {err}; make sure "
            "the package is installed or its folder is on PYTHONPATH",
            path="env.class",
        ) from err
    obj: Any = getattr(module, attr, None)
    if obj is None:
        public = [n for n in dir(module) if not n.startswith("_")]
        raise ConfigError(
            f"module '{module_name}' has no class '{attr}'{did_you_mean(attr, public)}",
            path="env.class",
        )
    if not (isinstance(obj, type) and issubclass(obj, Env)):
        raise ConfigError(f"'{name}' is not a subclass of flowrun.envs.Env", path="env.class")
    return obj


def register_envs() -> None:
    """Register every built-in env as ``flowrun/<Name>-v0`` with Gymnasium (idempotent)."""
    for name in env_names():
        env_id = f"flowrun/{name}-v0"
        if env_id in gymnasium.registry:
            continue
        gymnasium.register(
            id=env_id,
            entry_point="flowrun.envs.factory:make_registered",
            kwargs={"env_name": name},
            disable_env_checker=True,
        )
