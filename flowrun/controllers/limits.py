"""A vehicle type's acceleration limits as Flow's controllers read them (m/s^2)."""

from __future__ import annotations

from typing import Any

#: SUMO's default ``accel`` of a passenger car, m/s^2 (Flow's ``SumoCarFollowingParams``).
DEFAULT_MAX_ACCEL = 2.6

#: Flow's default ``decel`` of ``SumoCarFollowingParams``, m/s^2.
DEFAULT_MAX_DECEL = 7.5


def vehicle_limits(car_following_params: Any) -> tuple[float, float] | None:
    """``(accel, decel)`` (m/s^2, decel positive) of a vehicle type's car-following params.

    Reads Flow's ``controller_params['accel'/'decel']`` when present, else the ``accel`` and
    ``decel`` attributes (flowrun's :class:`~flowrun.config.params.SumoCarFollowingParams`).
    ``None`` when ``car_following_params`` is ``None`` or has neither.
    """
    if car_following_params is None:
        return None
    table = getattr(car_following_params, "controller_params", None)
    if isinstance(table, dict) and "accel" in table and "decel" in table:
        return float(table["accel"]), abs(float(table["decel"]))
    accel = getattr(car_following_params, "accel", None)
    decel = getattr(car_following_params, "decel", None)
    if accel is None or decel is None:
        return None
    return float(accel), abs(float(decel))
