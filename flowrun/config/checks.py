"""Value checks for single config fields: impossible values are errors, not surprises later.

:data:`FIELD_CHECKS` maps ``(class, field name)`` to a function that returns an error message
(what was expected, what was found) or ``None`` when the already type-checked value is fine.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from typing import Any

from flowrun.config.model import ExperimentConfig, TrainConfig
from flowrun.config.modes import (
    LANE_CHANGE_MODES,
    LEGACY_LANE_CHANGE_MODES,
    SPEED_MODES,
    legacy_lane_change_message,
)
from flowrun.config.params import (
    EnvParams,
    InFlow,
    InitialConfig,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    VehicleType,
)
from flowrun.config.vtype import LANE_CHANGE_MODELS
from flowrun.suggest import did_you_mean

Check = Callable[[Any], str | None]

ALGORITHMS = ("PPO", "A2C", "SAC", "TD3", "DDPG", "TRPO")
SPACINGS = ("uniform", "random", "custom")
SIM_BACKENDS = ("sumo", "numpy")
TRAIN_BACKENDS = ("sb3", "rllib")


def positive(hint: str = "") -> Check:
    """Require ``value > 0`` (``None`` passes: it means "not set")."""
    suffix = f"; {hint}" if hint else ""

    def check(value: Any) -> str | None:
        if value is None or value > 0:
            return None
        return f"must be greater than 0, got {value!r}{suffix}"

    return check


def at_least(low: float, hint: str = "") -> Check:
    """Require ``value >= low`` (``None`` passes: it means "not set")."""
    suffix = f"; {hint}" if hint else ""

    def check(value: Any) -> str | None:
        if value is None or value >= low:
            return None
        return f"must be at least {low:g}, got {value!r}{suffix}"

    return check


def between(low: float, high: float) -> Check:
    """Require ``low <= value <= high``."""

    def check(value: Any) -> str | None:
        if value is None or low <= value <= high:
            return None
        return f"must be between {low:g} and {high:g}, got {value!r}"

    return check


def one_of(kind: str, names: Collection[str], allow_int: bool = False) -> Check:
    """Require one of ``names`` (with a did-you-mean), or a non-negative int if ``allow_int``."""

    def check(value: Any) -> str | None:
        if isinstance(value, int) and allow_int:
            return None if value >= 0 else f"must be a name or an int >= 0, got {value}"
        if value in names:
            return None
        return (
            f"unknown {kind} '{value}'{did_you_mean(str(value), names)}; "
            f"expected one of: {', '.join(names)}"
            + (" (or an integer bit set)" if allow_int else "")
        )

    return check


def _name(value: Any) -> str | None:
    if not value:
        return "must not be empty"
    if any(c in value for c in "/\\") or value in (".", ".."):
        return f"names the run folder, so it must not contain '/' or '\\', got {value!r}"
    return None


def _lane_change_mode(value: Any) -> str | None:
    if isinstance(value, str) and value in LEGACY_LANE_CHANGE_MODES:
        return legacy_lane_change_message(value)
    return one_of("lane_change_mode", LANE_CHANGE_MODES, allow_int=True)(value)


def _not_empty(value: Any) -> str | None:
    return None if value is None or value else "must not be empty"


FIELD_CHECKS: dict[tuple[type, str], Check] = {
    (ExperimentConfig, "name"): _name,
    (SumoParams, "sim_step"): positive(),
    (SumoParams, "seed"): at_least(0),
    (SumoParams, "port"): between(0, 65535),
    (SumoParams, "num_clients"): at_least(1),
    (SumoParams, "sight_radius"): at_least(0),
    (SumoParams, "pxpm"): positive(),
    (SumoParams, "backend"): one_of("sim backend", SIM_BACKENDS),
    (EnvParams, "horizon"): positive("use .inf for no limit"),
    (EnvParams, "warmup_steps"): at_least(0),
    (EnvParams, "sims_per_step"): at_least(1),
    (EnvParams, "env_class"): _not_empty,
    (InitialConfig, "spacing"): one_of("spacing", SPACINGS),
    (InitialConfig, "min_gap"): at_least(0),
    (InitialConfig, "perturbation"): at_least(0),
    (InitialConfig, "lanes_distribution"): at_least(1, "use .inf for all lanes"),
    (VehicleType, "veh_id"): _not_empty,
    (VehicleType, "num_vehicles"): at_least(0),
    (VehicleType, "initial_speed"): at_least(0),
    (SumoCarFollowingParams, "speed_mode"): one_of("speed_mode", SPEED_MODES, allow_int=True),
    (SumoCarFollowingParams, "accel"): positive(),
    (SumoCarFollowingParams, "decel"): positive(),
    (SumoCarFollowingParams, "sigma"): between(0, 1),
    (SumoCarFollowingParams, "tau"): at_least(0),
    (SumoCarFollowingParams, "min_gap"): at_least(0),
    (SumoCarFollowingParams, "max_speed"): positive(),
    (SumoCarFollowingParams, "speed_factor"): positive(),
    (SumoCarFollowingParams, "speed_dev"): at_least(0),
    (SumoCarFollowingParams, "length"): positive(),
    (SumoLaneChangeParams, "lane_change_mode"): _lane_change_mode,
    (SumoLaneChangeParams, "model"): one_of("lane-change model", LANE_CHANGE_MODELS),
    (InFlow, "vehs_per_hour"): positive(),
    (InFlow, "probability"): between(0, 1),
    (InFlow, "period"): positive(),
    (InFlow, "begin"): at_least(1, "vehicles placed at reset come first"),
    (InFlow, "number"): at_least(1),
    (InFlow, "end"): at_least(0),
    (TrainConfig, "algorithm"): one_of("algorithm", ALGORITHMS),
    (TrainConfig, "total_timesteps"): at_least(1),
    (TrainConfig, "n_envs"): at_least(1),
    (TrainConfig, "seed"): at_least(0),
    (TrainConfig, "eval_freq"): at_least(0),
    (TrainConfig, "eval_episodes"): at_least(1),
    (TrainConfig, "checkpoint_freq"): at_least(0),
    (TrainConfig, "backend"): one_of("training backend", TRAIN_BACKENDS),
}

# Network parameters shared by Flow's networks; checked here when present, whatever the type.
# Everything network-specific is checked by ``flowrun.networks.registry.validate_network``.
NETWORK_NUMBERS: dict[str, tuple[type, Check]] = {
    "length": (float, positive()),
    "speed_limit": (float, positive()),
    "lanes": (int, at_least(1)),
    "resolution": (int, at_least(1)),
}
