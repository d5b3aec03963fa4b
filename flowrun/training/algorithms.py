"""The algorithms ``train.algorithm`` may name, and checks of their hyper-parameters.

Hyper-parameters use stable-baselines3's own argument names; they are checked against the
algorithm constructor's signature, so a typo is a :class:`ConfigError` with a did-you-mean.
Values that SB3 wants as objects are written as data and converted here: schedules
(:mod:`flowrun.config.schedules`), ``action_noise: {normal: 0.1}`` and
``train_freq: [1, episode]``.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from flowrun.config.schedules import SCHEDULE_PARAMS, parse_schedule
from flowrun.errors import ConfigError
from flowrun.suggest import did_you_mean, unknown_name
from flowrun.training.deps import require

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm

# name -> (module, class)
ALGORITHMS: dict[str, tuple[str, str]] = {
    "PPO": ("stable_baselines3", "PPO"),
    "A2C": ("stable_baselines3", "A2C"),
    "SAC": ("stable_baselines3", "SAC"),
    "TD3": ("stable_baselines3", "TD3"),
    "DDPG": ("stable_baselines3", "DDPG"),
    "TRPO": ("sb3_contrib", "TRPO"),
    # sb3-contrib's ARS, stopping between updates when asked (flowrun.training.ars)
    "ARS": ("flowrun.training.ars", "ARS"),
}
OFF_POLICY = ("SAC", "TD3", "DDPG")

# Constructor arguments flowrun sets itself, and the ``train:`` key that controls each.
RESERVED: dict[str, str] = {
    "policy": "train.policy",
    "env": "the config's env section",
    "policy_kwargs": "train.policy_kwargs",
    "seed": "train.seed (or --seed)",
    "tensorboard_log": "the run folder (always tensorboard/)",
    "verbose": "flowrun (progress is shown by the CLI)",
    "device": "flowrun (training runs on the CPU)",
    "_init_setup_model": "stable-baselines3",
}
NOISE_KINDS = ("normal", "ornstein_uhlenbeck")


def algorithm_class(name: str) -> type[BaseAlgorithm]:
    """The SB3 class of an algorithm name (imports the train extra)."""
    if name not in ALGORITHMS:
        raise ConfigError(
            unknown_name("algorithm", name, ALGORITHMS, sort=False), "train.algorithm"
        )
    module, cls = ALGORITHMS[name]
    found: type[BaseAlgorithm] = getattr(require(module), cls)
    return found


def accepted_hyperparams(cls: type) -> list[str]:
    """The constructor arguments of an SB3 class a config may set."""
    params = inspect.signature(cls.__init__).parameters  # type: ignore[misc]
    return [
        p for p, spec in params.items()
        if p != "self" and p not in RESERVED
        and spec.kind not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
    ]


def build_hyperparams(
    algorithm: str, hyperparams: Mapping[str, Any], action_dim: int | None = None
) -> dict[str, Any]:
    """Check ``train.hyperparams`` against the algorithm and convert data values to SB3's.

    Args:
        algorithm: the algorithm name.
        hyperparams: the config's mapping.
        action_dim: size of the action vector (needed for ``action_noise``).

    Raises:
        ConfigError: an unknown or reserved name, or a value that cannot be converted; the
            path is ``train.hyperparams.<name>``.
    """
    cls = algorithm_class(algorithm)
    accepted = accepted_hyperparams(cls)
    out: dict[str, Any] = {}
    for name, value in hyperparams.items():
        path = f"train.hyperparams.{name}"
        if name in RESERVED:
            raise ConfigError(f"'{name}' is set by {RESERVED[name]}, not here", path)
        if name not in accepted:
            raise ConfigError(
                f"{algorithm} has no hyper-parameter '{name}'{did_you_mean(name, accepted)}; "
                f"expected one of: {', '.join(sorted(accepted))}",
                path,
            )
        out[name] = _convert(name, value, path, action_dim)
    return out


def _convert(name: str, value: Any, path: str, action_dim: int | None) -> Any:
    if name in SCHEDULE_PARAMS:
        return parse_schedule(value, path)
    if name == "action_noise" and value is not None:
        return _action_noise(value, path, action_dim)
    if name == "train_freq" and isinstance(value, list):
        if len(value) != 2 or not isinstance(value[0], int) or value[1] not in ("step", "episode"):
            raise ConfigError(f"expected [n, step] or [n, episode], got {value!r}", path)
        return (value[0], value[1])
    return value


def _action_noise(value: Any, path: str, action_dim: int | None) -> Any:
    """``{normal: sigma}`` or ``{ornstein_uhlenbeck: sigma}`` -> an SB3 action-noise object."""
    if not isinstance(value, Mapping) or len(value) != 1:
        raise ConfigError(
            f"expected {{normal: sigma}} or {{ornstein_uhlenbeck: sigma}}, got {value!r}", path
        )
    ((kind, sigma),) = value.items()
    if kind not in NOISE_KINDS:
        raise ConfigError(unknown_name("action noise", str(kind), NOISE_KINDS, sort=False), path)
    if isinstance(sigma, bool) or not isinstance(sigma, int | float) or sigma < 0:
        raise ConfigError(f"expected a noise std >= 0, got {sigma!r}", f"{path}.{kind}")
    import numpy as np

    noise = require("stable_baselines3.common.noise")
    dim = action_dim or 1
    cls = noise.NormalActionNoise if kind == "normal" else noise.OrnsteinUhlenbeckActionNoise
    return cls(mean=np.zeros(dim), sigma=float(sigma) * np.ones(dim))
