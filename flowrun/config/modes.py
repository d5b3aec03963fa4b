"""Flow's speed modes and lane-change modes: names for SUMO's ``speedMode`` and
``laneChangeMode`` bit sets.

Flow stores a mode as SUMO's integer whatever it was given (a name or an int), and so does
flowrun: ``SumoCarFollowingParams(speed_mode="aggressive").speed_mode == 0``. The YAML may
use either spelling; a resolved config is written with the name where the int has one.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

from flowrun.errors import ConfigError
from flowrun.suggest import did_you_mean

log = logging.getLogger(__name__)

#: Flow's speed modes (SUMO ``speedMode`` bit sets).
SPEED_MODES: dict[str, int] = {
    "aggressive": 0,
    "obey_safe_speed": 1,
    "no_collide": 7,
    "right_of_way": 25,
    "all_checks": 31,
}

#: Flow's lane-change modes (SUMO ``laneChangeMode`` bit sets), as in Flow's last release.
#: ``_safe`` keeps SUMO's collision avoidance and safety gaps, ``_aggressive`` drops them.
LANE_CHANGE_MODES: dict[str, int] = {
    "no_lc_safe": 512,
    "no_lc_aggressive": 0,
    "sumo_default": 1621,
    "no_strategic_aggressive": 1108,
    "no_strategic_safe": 1620,
    "only_strategic_aggressive": 1,
    "only_strategic_safe": 513,
    "no_cooperative_aggressive": 1105,
    "no_cooperative_safe": 1617,
    "only_cooperative_aggressive": 4,
    "only_cooperative_safe": 516,
    "no_speed_gain_aggressive": 1093,
    "no_speed_gain_safe": 1605,
    "only_speed_gain_aggressive": 16,
    "only_speed_gain_safe": 528,
    "no_right_drive_aggressive": 1045,
    "no_right_drive_safe": 1557,
    "only_right_drive_aggressive": 64,
    "only_right_drive_safe": 576,
}

#: Lane-change mode names of Flow before 0.4 (``no_lat_collide`` 512, ``strategic`` 1621,
#: ``aggressive`` 0). Flow's last release no longer knows them: it logs an error and uses its
#: default ``no_lc_safe`` (512) — so does flowrun from Python, with a warning that says so.
#: The YAML refuses them (write the mode you mean).
LEGACY_LANE_CHANGE_MODES: dict[str, tuple[int, str]] = {
    "no_lat_collide": (512, "no_lc_safe"),
    "strategic": (1621, "sumo_default"),
    "aggressive": (0, "no_lc_aggressive"),
}
DEFAULT_LANE_CHANGE_MODE = LANE_CHANGE_MODES["no_lc_safe"]


def _as_int(value: Any, what: str) -> int | None:
    """``value`` as an int bit set if it is one (an int, or a float with an integral value)."""
    if isinstance(value, bool):
        raise ConfigError(
            f"must be a mode name or an integer bit set, got {value!r}", path=what
        )
    if isinstance(value, int):
        number = value
    elif isinstance(value, float) and value.is_integer():
        number = int(value)
    else:
        return None
    if number < 0:
        raise ConfigError(f"must be a mode name or an integer >= 0, got {value!r}", path=what)
    return number


def _unknown(what: str, value: Any, names: Mapping[str, int]) -> ConfigError:
    return ConfigError(
        f"unknown {what} {value!r}{did_you_mean(str(value), names)}; expected one of: "
        f"{', '.join(names)} (or an integer bit set)",
        path=what,
    )


def speed_mode_value(mode: Any) -> int:
    """SUMO's ``speedMode`` of a Flow speed-mode name or an int.

    Raises:
        ConfigError: an unknown name (with a did-you-mean) or a negative number.
    """
    number = _as_int(mode, "speed_mode")
    if number is not None:
        return number
    if isinstance(mode, str) and mode in SPEED_MODES:
        return SPEED_MODES[mode]
    raise _unknown("speed_mode", mode, SPEED_MODES)


def lane_change_mode_value(mode: Any) -> int:
    """SUMO's ``laneChangeMode`` of a Flow lane-change-mode name or an int.

    Flow's pre-0.4 names give what Flow's last release gives them (512, see
    :data:`LEGACY_LANE_CHANGE_MODES`), with a logged warning naming the mode to write.

    Raises:
        ConfigError: an unknown name (with a did-you-mean) or a negative number.
    """
    number = _as_int(mode, "lane_change_mode")
    if number is not None:
        return number
    if isinstance(mode, str) and mode in LANE_CHANGE_MODES:
        return LANE_CHANGE_MODES[mode]
    if isinstance(mode, str) and mode in LEGACY_LANE_CHANGE_MODES:
        log.warning("%s", legacy_lane_change_message(mode))
        return DEFAULT_LANE_CHANGE_MODE
    raise _unknown("lane_change_mode", mode, LANE_CHANGE_MODES)


def legacy_lane_change_message(mode: str) -> str:
    """What Flow's last release (and flowrun) does with an old lane-change mode name."""
    old, new = LEGACY_LANE_CHANGE_MODES[mode]
    return (
        f"lane_change_mode '{mode}' is a name of Flow before 0.4 (then {old}); Flow's last "
        f"release does not know it and uses its default no_lc_safe (512). Write '{new}' "
        f"({old}) for the old meaning, or 'no_lc_safe'"
    )


def mode_name(value: int | str, names: Mapping[str, int]) -> int | str:
    """The name of a mode bit set when it has one (``31`` -> ``"all_checks"``), else the int."""
    for name, number in names.items():
        if number == value:
            return name
    return value
