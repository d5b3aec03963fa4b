"""Value checks for single config fields: impossible values are errors, not surprises later.

:data:`FIELD_CHECKS` maps ``(class, field name)`` to a function that returns an error message
(what was expected, what was found) or ``None`` when the already type-checked value is fine.
"""

from __future__ import annotations

import math
import re
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
from flowrun.suggest import did_you_mean, unknown_name

Check = Callable[[Any], str | None]

ALGORITHMS = ("PPO", "A2C", "SAC", "TD3", "DDPG", "TRPO", "ARS")
SPACINGS = ("uniform", "random", "custom")
SIM_BACKENDS = ("sumo", "numpy")
TRAIN_BACKENDS = ("sb3", "rllib")
BEST_BY = ("speed_ratio", "return")


#: Largest magnitude accepted for a length, distance or position, m (1000 km).
MAX_METRES = 1e6
#: Largest speed accepted, m/s (far above any road; beyond it a value is a typo or overflow).
MAX_SPEED = 1e3
#: Largest simulation step, s (SUMO's models are written for steps of a second or less).
MAX_STEP = 10.0
#: Most vehicles in one group or inflow (SUMO handles tens of thousands; more is a typo).
MAX_VEHICLES = 100_000
#: Longest experiment name (it names a folder; file systems allow 255 bytes).
MAX_NAME = 100
#: Most steps of a horizon or warm-up.
MAX_STEPS = 10**9


def _finite(value: Any, allow_inf: bool) -> str | None:
    """A message for NaN, and for +-inf unless ``allow_inf``; ``None`` for other values."""
    if not isinstance(value, float):
        return None
    if math.isnan(value):
        return "must be a number, got .nan"
    if math.isinf(value) and not allow_inf:
        return f"must be finite, got {value!r}"
    return None


def _upper(value: Any, high: float | None, unit: str) -> str | None:
    if high is None or value is None or isinstance(value, bool) or value <= high:
        return None
    if math.isinf(value):
        return None  # allowed (``allow_inf``): infinity means "no limit"
    return f"must be at most {high:g}{unit}, got {value!r}"


def positive(hint: str = "", high: float | None = None, unit: str = "",
             allow_inf: bool = False) -> Check:
    """Require a finite ``value > 0`` (``None`` passes: it means "not set").

    Args:
        hint: appended to the message (how to fix it).
        high: largest value that makes sense, if any.
        unit: unit of ``high`` in the message (`` m``).
        allow_inf: accept ``.inf`` (it means "no limit").
    """
    suffix = f"; {hint}" if hint else ""

    def check(value: Any) -> str | None:
        if value is None:
            return None
        problem = _finite(value, allow_inf)
        if problem is None and not value > 0:
            problem = f"must be greater than 0, got {value!r}"
        problem = problem or _upper(value, high, unit)
        return f"{problem}{suffix}" if problem else None

    return check


def at_least(low: float, hint: str = "", high: float | None = None, unit: str = "",
             allow_inf: bool = False) -> Check:
    """Require a finite ``value >= low`` (``None`` passes: it means "not set"); see
    :func:`positive` for the other arguments."""
    suffix = f"; {hint}" if hint else ""

    def check(value: Any) -> str | None:
        if value is None:
            return None
        problem = _finite(value, allow_inf)
        if problem is None and not value >= low:
            problem = f"must be at least {low:g}, got {value!r}"
        problem = problem or _upper(value, high, unit)
        return f"{problem}{suffix}" if problem else None

    return check


def between(low: float, high: float) -> Check:
    """Require ``low <= value <= high`` (NaN fails)."""

    def check(value: Any) -> str | None:
        if value is None or low <= value <= high:
            return None
        return f"must be between {low:g} and {high:g}, got {value!r}"

    return check


def magnitude(high: float, unit: str = "") -> Check:
    """Require a finite value with ``|value| <= high`` (any sign)."""

    def check(value: Any) -> str | None:
        if value is None:
            return None
        problem = _finite(value, False)
        if problem is None and abs(value) > high:
            problem = f"must be between {-high:g} and {high:g}{unit}, got {value!r}"
        return problem

    return check


def _steps(value: Any) -> str | None:
    """``env.horizon``: a whole number of steps >= 1, or ``.inf``."""
    problem = positive("use .inf for no limit", high=MAX_STEPS, allow_inf=True)(value)
    if problem is None and math.isfinite(value) and value != int(value):
        problem = f"must be a whole number of steps, got {value!r}"
    return problem


def _sim_step(value: Any) -> str | None:
    """SUMO counts time in milliseconds: a step is a whole number of them, at most 10 s."""
    problem = positive(high=MAX_STEP, unit=" s")(value)
    if problem is None and abs(value * 1000 - round(value * 1000)) > 1e-6:
        problem = f"must be a whole number of milliseconds (SUMO's time unit), got {value!r}"
    return problem


#: Flow's pyglet render modes (``SumoParams(render="drgb")``): frames drawn by flowrun
FRAME_RENDER_MODES = ("rgb", "drgb", "gray", "dgray")


def _render(value: Any) -> str | None:
    if isinstance(value, bool) or value in FRAME_RENDER_MODES:
        return None
    return (
        f"expected true, false or one of Flow's frame modes {', '.join(FRAME_RENDER_MODES)}, "
        f"got {value!r}{did_you_mean(str(value), FRAME_RENDER_MODES)}"
    )


def _teleport_time(value: Any) -> str | None:
    """SUMO ``--time-to-teleport``: finite seconds; a negative value turns teleporting off."""
    problem = _finite(value, False)
    if problem:
        return f"{problem}; use -1 to turn teleporting off"
    return None


def _color(value: Any) -> str | None:
    """A colour SUMO reads: a name, ``r,g,b[,a]`` (0-255, or 0-1 floats) or ``#rrggbb[aa]``."""
    if value is None or value.lower() in SUMO_COLOURS:
        return None
    if re.fullmatch(r"#(?:[0-9a-fA-F]{6}|[0-9a-fA-F]{8})", value):
        return None
    parts = value.split(",")
    if len(parts) in (3, 4):
        try:
            numbers = [float(p) for p in parts]
        except ValueError:
            numbers = []
        if numbers and all(0 <= x <= 255 for x in numbers):
            return None
    return (
        f"SUMO cannot read the colour {value!r}; write a name ({', '.join(SUMO_COLOURS[:6])}, "
        "...), 'r,g,b' with 0-255 values (or 0-1 floats), or '#rrggbb'"
    )


#: Colour names SUMO knows (``RGBColor::parseColor``).
SUMO_COLOURS = ("red", "green", "blue", "yellow", "cyan", "magenta", "orange", "white",
                "black", "grey", "gray", "invisible", "random")  # fmt: skip
#: Characters SUMO refuses in a vehicle or vehicle-type id (``SUMOXMLDefinitions``).
SUMO_ID_FORBIDDEN = " \t\n\r|\\'\";,<>&"


#: SUMO's ``departSpeed`` keywords.
DEPART_SPEEDS = ("random", "max", "desired", "speedLimit", "last", "avg")


def _depart_speed(value: Any) -> str | None:
    if isinstance(value, str):
        if value in DEPART_SPEEDS:
            return None
        return f"{one_of('departure speed', DEPART_SPEEDS)(value)} (or a speed in m/s)"
    return at_least(0, high=MAX_SPEED, unit=" m/s")(value)


#: SUMO's ``departLane`` keywords.
DEPART_LANES = ("first", "random", "free", "allowed", "best")


def _depart_lane(value: Any) -> str | None:
    if isinstance(value, str):
        if value in DEPART_LANES:
            return None
        return f"{one_of('departure lane', DEPART_LANES)(value)} (or a lane index >= 0)"
    return at_least(0)(value)


def _vehicle_id(value: Any) -> str | None:
    if not value:
        return "must not be empty"
    bad = sorted({c for c in value if c in SUMO_ID_FORBIDDEN or not c.isprintable()})
    if bad:
        shown = ", ".join(repr(c) for c in bad)
        return (
            f"SUMO refuses the character(s) {shown} in vehicle ids, got {value!r}; use letters, "
            "digits, '_', '-' or '.'"
        )
    return None


def one_of(kind: str, names: Collection[str], allow_int: bool = False) -> Check:
    """Require one of ``names`` (with a did-you-mean), or a non-negative int if ``allow_int``."""

    def check(value: Any) -> str | None:
        if isinstance(value, int) and allow_int:
            return None if value >= 0 else f"must be a name or an int >= 0, got {value}"
        if value in names:
            return None
        bits = " (or an integer bit set)" if allow_int else ""
        return unknown_name(kind, str(value), names, sort=False) + bits

    return check


def _name(value: Any) -> str | None:
    if not value:
        return "must not be empty"
    if any(c in value for c in "/\\") or value in (".", ".."):
        return f"names the run folder, so it must not contain '/' or '\\', got {value!r}"
    if any(c in value for c in ",:"):
        return (
            f"names the run folder, and SUMO's tools read ',' and ':' in a file path as a "
            f"list or a host:port, so it must not contain them, got {value!r}"
        )
    if not value.isprintable() or len(value) > MAX_NAME:
        return (
            f"names the run folder, so it must be printable text of at most {MAX_NAME} "
            f"characters, got {value[:40]!r}{'...' if len(value) > 40 else ''}"
        )
    return None


def _lane_change_mode(value: Any) -> str | None:
    if isinstance(value, str) and value in LEGACY_LANE_CHANGE_MODES:
        return legacy_lane_change_message(value)
    return one_of("lane_change_mode", LANE_CHANGE_MODES, allow_int=True)(value)


def _not_empty(value: Any) -> str | None:
    return None if value is None or value else "must not be empty"


M, SPEED = " m", " m/s"
#: Largest seed: numpy's legacy seeding (SB3) takes < 2**32, SUMO's --seed is a C int; the
#: seeds of parallel envs and evaluation episodes count up from it.
MAX_SEED = 2**31 - 1


def _seed(value: Any) -> str | None:
    if value is None or isinstance(value, bool) or not isinstance(value, int):
        return at_least(0)(value)
    if not 0 <= value <= MAX_SEED:
        return f"must be between 0 and {MAX_SEED}, got {value}"
    return None


FIELD_CHECKS: dict[tuple[type, str], Check] = {
    (ExperimentConfig, "name"): _name,
    (SumoParams, "sim_step"): _sim_step,
    (SumoParams, "seed"): _seed,
    (SumoParams, "port"): between(0, 65535),
    (SumoParams, "num_clients"): at_least(1),
    (SumoParams, "sight_radius"): at_least(0, high=MAX_METRES, unit=M),
    (SumoParams, "pxpm"): positive(high=1e4),
    (SumoParams, "backend"): one_of("sim backend", SIM_BACKENDS),
    (SumoParams, "render"): _render,
    (SumoParams, "teleport_time"): _teleport_time,
    (SumoParams, "lateral_resolution"): positive(high=100, unit=M),
    (EnvParams, "horizon"): _steps,
    (EnvParams, "warmup_steps"): at_least(0, high=MAX_STEPS),
    (EnvParams, "sims_per_step"): at_least(1, high=10_000),
    (EnvParams, "env_class"): _not_empty,
    (InitialConfig, "spacing"): one_of("spacing", SPACINGS),
    (InitialConfig, "min_gap"): at_least(0, high=MAX_METRES, unit=M),
    (InitialConfig, "perturbation"): at_least(0, high=MAX_METRES, unit=M),
    (InitialConfig, "x0"): magnitude(MAX_METRES, M),
    (InitialConfig, "bunching"): magnitude(MAX_METRES, M),
    # below 1 counts as 1 (with a warning when placing), as in Flow
    (InitialConfig, "lanes_distribution"): lambda value: _finite(value, True),
    (VehicleType, "veh_id"): _vehicle_id,
    (VehicleType, "num_vehicles"): at_least(0, high=MAX_VEHICLES),
    (VehicleType, "initial_speed"): at_least(0, high=MAX_SPEED, unit=SPEED),
    (VehicleType, "color"): _color,
    (SumoCarFollowingParams, "speed_mode"): one_of("speed_mode", SPEED_MODES, allow_int=True),
    (SumoCarFollowingParams, "accel"): positive(high=1e3, unit=" m/s^2"),
    (SumoCarFollowingParams, "decel"): positive(high=1e3, unit=" m/s^2"),
    (SumoCarFollowingParams, "sigma"): between(0, 1),
    (SumoCarFollowingParams, "tau"): at_least(0, high=1e3, unit=" s"),
    (SumoCarFollowingParams, "min_gap"): at_least(0, high=MAX_METRES, unit=M),
    (SumoCarFollowingParams, "max_speed"): positive(high=MAX_SPEED, unit=SPEED),
    (SumoCarFollowingParams, "speed_factor"): positive(high=100),
    (SumoCarFollowingParams, "speed_dev"): at_least(0, high=100),
    (SumoCarFollowingParams, "impatience"): between(0, 1),
    (SumoCarFollowingParams, "length"): positive(high=1e4, unit=M),
    (SumoLaneChangeParams, "lane_change_mode"): _lane_change_mode,
    (SumoLaneChangeParams, "model"): one_of("lane-change model", LANE_CHANGE_MODELS),
    (InFlow, "vehs_per_hour"): positive(high=1e6),
    (InFlow, "probability"): between(0, 1),
    (InFlow, "period"): positive(high=1e9, unit=" s"),
    (InFlow, "begin"): at_least(1, "vehicles placed at reset come first", high=1e9),
    (InFlow, "number"): at_least(1, high=MAX_VEHICLES),
    (InFlow, "end"): at_least(0, high=1e9),
    (InFlow, "depart_speed"): _depart_speed,
    (InFlow, "depart_lane"): _depart_lane,
    (InFlow, "name"): _vehicle_id,
    (TrainConfig, "algorithm"): one_of("algorithm", ALGORITHMS),
    (TrainConfig, "total_timesteps"): at_least(1, high=1e13),
    (TrainConfig, "n_envs"): at_least(1, high=1024),
    (TrainConfig, "seed"): _seed,
    (TrainConfig, "eval_freq"): at_least(0),
    (TrainConfig, "eval_episodes"): at_least(1, high=1e6),
    (TrainConfig, "eval_backend"): one_of("evaluation backend", SIM_BACKENDS),
    (TrainConfig, "best_by"): one_of("best-model score", BEST_BY),
    (TrainConfig, "checkpoint_freq"): at_least(0),
    (TrainConfig, "backend"): one_of("training backend", TRAIN_BACKENDS),
}

#: Float fields whose default is infinite (or which mean "no limit" at .inf): the only floats
#: that may be .inf. Every float field refuses .nan (see ``Converter``).
INFINITE_OK: frozenset[tuple[type, str]] = frozenset({
    (EnvParams, "horizon"),
    (InitialConfig, "lanes_distribution"),
    (SumoLaneChangeParams, "lc_time_to_impatience"),
})  # fmt: skip

#: Float fields (so that they may be .inf) that count steps: a finite value is kept as an int.
WHOLE_OR_INF: frozenset[tuple[type, str]] = frozenset({(EnvParams, "horizon")})

# Network parameters shared by Flow's networks; checked here when present, whatever the type.
# Everything network-specific is checked by ``flowrun.networks.registry.validate_network``.
NETWORK_NUMBERS: dict[str, tuple[type, Check]] = {
    "length": (float, positive(high=MAX_METRES, unit=" m")),
    "speed_limit": (float, positive(high=MAX_SPEED, unit=" m/s")),
    "lanes": (int, at_least(1)),
    "resolution": (int, at_least(1)),
}
