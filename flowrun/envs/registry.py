"""Environment classes by name, user classes by import path, and Gymnasium registration.

The multi-agent envs (:mod:`flowrun.multiagent`, PettingZoo ``ParallelEnv``s above this layer)
are listed here by name and import path and imported only when a config names one, so
flowrun's core installs and imports without PettingZoo.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from flowrun.errors import ConfigError
from flowrun.import_path import import_near
from flowrun.suggest import did_you_mean, unknown_name

if TYPE_CHECKING:
    from flowrun.envs.base import Env

#: ``env.class`` name -> ``module:Class`` of each multi-agent environment.
MULTIAGENT_ENVS: dict[str, str] = {
    "MultiAgentWaveAttenuationPOEnv": "flowrun.multiagent.ring:MultiAgentWaveAttenuationPOEnv",
    "MultiWaveAttenuationPOEnv": "flowrun.multiagent.rings:MultiWaveAttenuationPOEnv",
    "AdversarialAccelEnv": "flowrun.multiagent.adversarial:AdversarialAccelEnv",
    "I210MultiEnv": "flowrun.multiagent.i210:I210MultiEnv",
    "MultiAgentAccelPOEnv": "flowrun.multiagent.ring:MultiAgentAccelPOEnv",
    "MultiAgentMergePOEnv": "flowrun.multiagent.merge:MultiAgentMergePOEnv",
    "MultiAgentHighwayPOEnv": "flowrun.multiagent.highway:MultiAgentHighwayPOEnv",
    "MultiTrafficLightGridPOEnv": "flowrun.multiagent.grid:MultiTrafficLightGridPOEnv",
}

#: The command that installs what the multi-agent environments need.
INSTALL_HINT = "pip install 'flowrun[multiagent]'  (or: pip install pettingzoo==1.27.0)"


#: The names of flowrun's own environment classes (each registered under its class name),
#: listed without importing the classes (``env_classes`` imports them).
ENV_NAMES: tuple[str, ...] = (
    "AccelEnv",
    "WaveAttenuationEnv",
    "WaveAttenuationPOEnv",
    "LaneChangeAccelEnv",
    "LaneChangeAccelPOEnv",
    "MergePOEnv",
    "BottleneckEnv",
    "BottleneckAccelEnv",
    "BottleneckDesiredVelocityEnv",
    "TestEnv",
    "TrafficLightGridEnv",
    "TrafficLightGridPOEnv",
    "TrafficLightGridBenchmarkEnv",
)
#: Flow's old names of some of them -> the class name.
ALIAS_NAMES: dict[str, str] = {"DesiredVelocityEnv": "BottleneckDesiredVelocityEnv"}


def env_classes() -> tuple[type[Env], ...]:
    """flowrun's own environment classes, in the order of :data:`ENV_NAMES`."""
    return tuple(_builtin_class(name) for name in ENV_NAMES)


def _builtin_class(name: str) -> type[Env]:
    """A built-in env class by name or alias, importing only its module (listing the
    names imports none)."""
    name = ALIAS_NAMES.get(name, name)
    cls: type[Env] = getattr(_env_module(name), name)
    return cls


def _env_module(name: str) -> ModuleType:
    if name.startswith("Bottleneck"):
        from flowrun.envs import bottleneck

        return bottleneck
    if name.startswith("TrafficLightGrid"):
        from flowrun.envs import traffic_light_grid

        return traffic_light_grid
    if name.startswith("WaveAttenuation"):
        from flowrun.envs.ring import wave_attenuation

        return wave_attenuation
    if name.startswith("LaneChange"):
        from flowrun.envs.ring import lane_change

        return lane_change
    if name == "MergePOEnv":
        from flowrun.envs import merge

        return merge
    if name == "TestEnv":
        from flowrun.envs import test

        return test
    from flowrun.envs.ring import accel

    return accel


def env_names() -> list[str]:
    """Names a config may use as ``env.class`` (the multi-agent ones need PettingZoo)."""
    return sorted([*ENV_NAMES, *ALIAS_NAMES, *MULTIAGENT_ENVS])


def _multiagent_class(name: str) -> type | None:
    """A multi-agent env class by name (``None`` for other names), imported on demand."""
    path = MULTIAGENT_ENVS.get(name)
    if path is None:
        return None
    module_name, _, attr = path.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as err:
        if err.name != "pettingzoo":
            raise
        raise ConfigError(
            f"{name} is a PettingZoo multi-agent environment and PettingZoo is not "
            f"installed; install it with: {INSTALL_HINT}",
            path="env.class",
        ) from None
    cls: type = getattr(module, attr)
    return cls


def resolve_env_class(name: str | None, search_dir: str | Path | None = None) -> type:
    """The environment class for a built-in name or an import path ``package.module:Class``.

    Args:
        name: a built-in env name (``WaveAttenuationPOEnv``) or ``package.module:Class``;
            ``None`` means ``AccelEnv``.
        search_dir: a folder to import the package from when it is not importable already
            (the config file's folder): it is appended to ``sys.path``, so an installed
            package of the same name wins.

    Raises:
        ConfigError: unknown name or failed import (with did-you-mean).
    """
    if name is None:
        name = "AccelEnv"
    multiagent = _multiagent_class(name)
    if multiagent is not None:
        return multiagent
    if ":" not in name:
        if name not in ENV_NAMES and name not in ALIAS_NAMES:
            raise ConfigError(
                unknown_name("environment", name, env_names())
                + ", or an import path 'package.module:Class'",
                path="env.class",
            )
        return _builtin_class(name)
    module_name, _, attr = name.partition(":")
    folder = None if search_dir is None else Path(search_dir)
    module = import_near(module_name, name, folder, "environment", "env.class")
    return _env_class(module, module_name, attr, name)


def _env_class(module: ModuleType, module_name: str, attr: str, name: str) -> type:
    from flowrun.envs.base import Env

    obj: Any = getattr(module, attr, None)
    if obj is None:
        envs = [  # classes defined here under their own name (no aliases or imports)
            n
            for n, v in vars(module).items()
            if isinstance(v, type)
            and issubclass(v, Env)
            and v.__module__ == module.__name__
            and v.__name__ == n
        ]
        public = envs or [n for n in dir(module) if not n.startswith("_")]
        listed = f"; it defines {', '.join(sorted(envs))}" if envs else ""
        raise ConfigError(
            f"module '{module_name}' has no class '{attr}'{did_you_mean(attr, public)}{listed}",
            path="env.class",
        )
    if not (isinstance(obj, type) and issubclass(obj, Env)):
        raise ConfigError(f"'{name}' is not a subclass of flowrun.envs.Env", path="env.class")
    return obj


def register_envs() -> None:
    """Register every built-in env as ``flowrun/<Name>-v0`` with Gymnasium (idempotent).

    Without a ``config`` an env runs the experiment it comes with
    (:func:`flowrun.envs.factory.default_experiment`).
    """
    import gymnasium

    # the multi-agent envs are PettingZoo envs, not Gymnasium's
    for name in sorted([*ENV_NAMES, *ALIAS_NAMES]):
        env_id = f"flowrun/{name}-v0"
        if env_id in gymnasium.registry:
            continue
        gymnasium.register(
            id=env_id,
            entry_point="flowrun.envs.factory:make_registered",
            kwargs={"env_name": name},
            disable_env_checker=True,
        )
