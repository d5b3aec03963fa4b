"""Flow's longitudinal fail-safes, as pure functions over arrays.

Each takes the requested accelerations (m/s^2) and returns a possibly reduced copy. They run
after the noise, in the order the user listed them, exactly as Flow's ``get_action`` does.
``nan`` entries pass through untouched (a comparison with ``nan`` is false).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flowrun.controllers.params import ParameterValueError
from flowrun.suggest import did_you_mean
from flowrun.types import CarFollowingInputs, FloatArray

FAIL_SAFES = ("instantaneous", "safe_velocity", "feasible_accel", "obey_speed_limit")


def check_fail_safe(fail_safe: str | Sequence[str] | None) -> tuple[str, ...]:
    """Normalise Flow's ``fail_safe`` argument (a name, a list of names, or ``None``).

    Raises:
        ValueError: for an unknown name (with a did-you-mean) or a wrong type.
    """
    if fail_safe is None:
        return ()
    if not isinstance(fail_safe, str | Sequence):
        raise ParameterValueError(
            f"fail_safe {fail_safe!r} is a {type(fail_safe).__name__}; give a name or a list "
            "of names of: " + ", ".join(FAIL_SAFES),
            "fail_safe",
        )
    names = [fail_safe] if isinstance(fail_safe, str) else list(fail_safe)
    for name in names:
        if not isinstance(name, str) or name not in FAIL_SAFES:
            hint = did_you_mean(name, FAIL_SAFES) if isinstance(name, str) else ""
            raise ParameterValueError(
                f"unknown fail_safe {name!r}{hint}; expected one of: " + ", ".join(FAIL_SAFES),
                "fail_safe",
            )
    return tuple(names)


def instantaneous(accel: FloatArray, v: FloatArray, h: FloatArray, dt: float) -> FloatArray:
    """Stop at once when the next step could reach a leader that stood still.

    With ``v_next = v + a*dt > 0``: if ``h < dt*v_next + 1e-3*v + 0.5*v*dt`` (m), return
    ``-v/dt`` (stop within one step); otherwise keep ``a``. Vehicles without a leader
    (``h = inf``) are never affected.
    """
    v_next = v + accel * dt
    danger = (v_next > 0) & (h < dt * v_next + 1e-3 * v + 0.5 * v * dt)
    return np.where(danger, -v / dt, accel)


def safe_velocity(
    accel: FloatArray, v: FloatArray, h: FloatArray, v_lead: FloatArray, dt: float, delay: float
) -> FloatArray:
    """Cap the next speed at Flow's safe velocity ``2*h/dt + (v_lead - v) - 2*v*delay`` (m/s).

    If ``v + a*dt`` exceeds it, return ``(v_safe - v)/dt``, or ``-v/dt`` when ``v_safe <= 0``.
    """
    v_safe = 2.0 * h / dt + (v_lead - v) - 2.0 * v * delay
    capped = np.where(v_safe > 0, (v_safe - v) / dt, -v / dt)
    return np.where(v + accel * dt > v_safe, capped, accel)


def obey_speed_limit(
    accel: FloatArray, v: FloatArray, speed_limit: FloatArray, dt: float
) -> FloatArray:
    """Keep the next speed ``v + a*dt`` at or below the lane's speed limit (m/s).

    Above it, return ``(limit - v)/dt``; a limit ``<= 0`` stops the car: ``-v/dt`` (Flow).
    """
    capped = np.where(speed_limit > 0, (speed_limit - v) / dt, -v / dt)
    return np.where(v + accel * dt > speed_limit, capped, accel)


def feasible_accel(
    accel: FloatArray, max_accel: FloatArray | None, max_decel: FloatArray | None
) -> FloatArray:
    """Clip to ``[-max_decel, max_accel]`` (m/s^2); a bound that is ``None`` is not applied."""
    out = accel
    if max_accel is not None:
        out = np.where(out > max_accel, max_accel, out)
    if max_decel is not None:
        out = np.where(out < -np.abs(max_decel), -np.abs(max_decel), out)
    return out


def apply_fail_safes(
    names: Sequence[str], accel: FloatArray, inputs: CarFollowingInputs, delay: float
) -> FloatArray:
    """Run the named fail-safes in order on ``accel``."""
    out = accel
    for name in names:
        if name == "instantaneous":
            out = instantaneous(out, inputs.speed, inputs.headway, inputs.dt)
        elif name == "safe_velocity":
            out = safe_velocity(
                out, inputs.speed, inputs.headway, inputs.leader_speed, inputs.dt, delay
            )
        elif name == "obey_speed_limit":
            out = obey_speed_limit(out, inputs.speed, inputs.speed_limit, inputs.dt)
        else:
            out = feasible_accel(out, inputs.max_accel, inputs.max_decel)
    return out
