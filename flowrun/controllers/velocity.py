"""Velocity controllers from Stern et al. (2018), "Dissipation of stop-and-go waves via control
of autonomous vehicles: Field experiments" (https://arxiv.org/abs/1705.01693).

Both compute a commanded speed ``v_cmd`` (m/s) and turn it into the acceleration that reaches
it in one step, ``(v_cmd - v)/dt`` (m/s^2).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from flowrun.controllers.base import (
    CAR_FOLLOWING_PARAMS,
    DISPLAY_WARNINGS,
    FAIL_SAFE,
    NOISE,
    VEH_ID,
    AccelerationController,
    FailSafe,
)
from flowrun.controllers.params import declared, number, option, param
from flowrun.types import CarFollowingInputs, FloatArray


def _edges(owner: str, name: str, value: Any) -> frozenset[str]:
    return frozenset(value or ())


def _interval(owner: str, name: str, value: Any) -> tuple[float, float] | None:
    if value is None:
        return None
    lo, hi = (number(owner, name, x) for x in value)
    return lo, hi


def follower_stopper_speed(
    v: FloatArray,
    h: FloatArray,
    v_lead: FloatArray,
    *,
    v_des: float,
    dx_1_0: float = 4.5,
    dx_2_0: float = 5.25,
    dx_3_0: float = 6.0,
    d_1: float = 1.5,
    d_2: float = 1.0,
    d_3: float = 0.5,
) -> FloatArray:
    """FollowerStopper commanded speed (m/s).

    With ``dv- = min(v_lead - v, 0)`` and the switching gaps
    ``dx_k = dx_k_0 + dv-^2 / (2*d_k)`` (m; ``d_k`` in m/s^2), and
    ``u = min(max(v_lead, 0), v_des)``::

        v_cmd = 0                                      if h <= dx_1
                u * (h - dx_1)/(dx_2 - dx_1)           if dx_1 < h <= dx_2
                u + (v_des - u)*(h - dx_2)/(dx_3 - dx_2)  if dx_2 < h <= dx_3
                v_des                                  otherwise (also without leader)

    (the paper's continuous form; Flow's code uses the ego speed instead of ``u`` inside the
    third branch's ``v_des - u``).
    """
    dv_minus = np.minimum(v_lead - v, 0.0)
    dx_1 = dx_1_0 + dv_minus**2 / (2.0 * d_1)
    dx_2 = dx_2_0 + dv_minus**2 / (2.0 * d_2)
    dx_3 = dx_3_0 + dv_minus**2 / (2.0 * d_3)
    u = np.minimum(np.maximum(v_lead, 0.0), v_des)
    finite_h = np.where(np.isfinite(h), h, dx_3 + 1.0)
    ramp_1 = u * (finite_h - dx_1) / (dx_2 - dx_1)
    ramp_2 = u + (v_des - u) * (finite_h - dx_2) / (dx_3 - dx_2)
    return np.select(
        [h <= dx_1, h <= dx_2, h <= dx_3],
        [np.zeros_like(v), ramp_1, ramp_2],
        default=v_des,
    )


@dataclass(eq=False)
class FollowerStopper(AccelerationController):
    """Stern et al.'s FollowerStopper (see :func:`follower_stopper_speed`).

    ``danger_edges`` and ``control_length`` say where Flow hands the car back to SUMO (read
    by :class:`~flowrun.controllers.view.VehicleControllerView`; the formula knows no
    edges). Flow's FollowerStopper always runs the ``safe_velocity`` fail-safe; so does the
    default here. The command is clipped to ``[-max_decel, max_accel]``, the vehicle type's
    limits (as Flow clips it), when they are known.
    """

    registered_name = "FollowerStopper"

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)
    v_des: float = param(15, "m/s", "desired speed", low=0)
    danger_edges: Collection[str] | None = option(None, "edges near whose end SUMO drives", _edges)
    control_length: Sequence[float] | None = option(
        None, "(x_start, x_end) outside which SUMO drives", _interval, unit="m"
    )
    dx_1_0: float = param(4.5, "m", "gap below which the command is 0", low=0)
    dx_2_0: float = param(5.25, "m", "gap of the first ramp's end", low="dx_1_0", strict=True)
    dx_3_0: float = param(6.0, "m", "gap above which the command is v_des", low="dx_2_0",
                          strict=True)  # fmt: skip
    d_1: float = param(1.5, "m/s^2", "deceleration widening dx_1", low=0, strict=True)
    d_2: float = param(1.0, "m/s^2", "deceleration widening dx_2", low=0, strict=True)
    d_3: float = param(0.5, "m/s^2", "deceleration widening dx_3", low=0, strict=True)
    noise: float = declared(NOISE)
    fail_safe: FailSafe = declared(FAIL_SAFE, default="safe_velocity")
    display_warnings: bool = declared(DISPLAY_WARNINGS)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        v_cmd = follower_stopper_speed(
            inputs.speed, inputs.headway, inputs.leader_speed,
            v_des=self.v_des, dx_1_0=self.dx_1_0, dx_2_0=self.dx_2_0, dx_3_0=self.dx_3_0,
            d_1=self.d_1, d_2=self.d_2, d_3=self.d_3,
        )  # fmt: skip
        accel = (v_cmd - inputs.speed) / inputs.dt
        if inputs.max_accel is not None:
            accel = np.minimum(accel, inputs.max_accel)
        if inputs.max_decel is not None:
            accel = np.maximum(accel, -np.abs(inputs.max_decel))
        return accel


def pi_saturation_speed(
    v: FloatArray,
    h: FloatArray,
    v_lead: FloatArray,
    u_mean: FloatArray,
    v_cmd_prev: FloatArray,
    *,
    v_catch: float = 1.0,
    g_l: float = 7.0,
    g_u: float = 30.0,
    gamma: float = 2.0,
) -> FloatArray:
    """One step of the PI-with-saturation commanded speed (m/s).

    ``v_target = U + v_catch*clip((h - g_l)/(g_u - g_l), 0, 1)``, with ``U`` the mean speed
    over the history window; ``dx_s = max(2*(v_lead - v), 4)`` (m);
    ``alpha = clip((h - dx_s)/gamma, 0, 1)``, ``beta = 1 - alpha/2``; and
    ``v_cmd = beta*(alpha*v_target + (1 - alpha)*v_lead) + (1 - beta)*v_cmd_prev``.
    Gaps g_l, g_u, gamma in m; ``h = inf`` (no leader) gives alpha = 1.
    """
    v_target = u_mean + v_catch * np.clip((h - g_l) / (g_u - g_l), 0.0, 1.0)
    dx_s = np.maximum(2.0 * (v_lead - v), 4.0)
    alpha = np.clip((h - dx_s) / gamma, 0.0, 1.0)
    beta = 1.0 - 0.5 * alpha
    return beta * (alpha * v_target + (1.0 - alpha) * v_lead) + (1.0 - beta) * v_cmd_prev


@dataclass(eq=False)
class PISaturation(AccelerationController):
    """Stern et al.'s proportional-integral controller with saturation (stateful).

    Memory per vehicle: the ego speeds of the last ``history_time`` seconds (their mean is
    the estimate ``U`` of the average traffic speed, as in Flow) and the previous command
    ``v_cmd`` (starting at 0). Flow keeps ``int(38/dt) - 1`` speeds (it drops the oldest
    when the list reaches ``int(38/dt)``); so does this class, with ``round`` for ``int``
    so that a ``history_time/dt`` like ``2.9999999`` counts as 3. :meth:`reset` clears the
    memory; a change in the number of vehicles also resets it.

    The acceleration is capped at the vehicle type's ``accel`` (``inputs.max_accel``, or the
    ``car_following_params`` given) as in Flow, which does not cap the deceleration.
    """

    registered_name = "PISaturation"
    stateful = True

    veh_id: str | None = declared(VEH_ID)
    car_following_params: Any = declared(CAR_FOLLOWING_PARAMS)
    v_catch: float = param(1, "m/s", "catch-up speed added at large gaps", low=0)
    g_l: float = param(7, "m", "gap where the catch-up speed starts", low=0)
    g_u: float = param(30, "m", "gap where it is complete", low="g_l", strict=True)
    gamma: float = param(2, "m", "gap width of the blend from the leader's speed", low=0,
                         strict=True)  # fmt: skip
    history_time: float = param(38, "s", "length of the speed history", low=0, strict=True)
    noise: float = declared(NOISE)
    fail_safe: FailSafe = declared(FAIL_SAFE)
    display_warnings: bool = declared(DISPLAY_WARNINGS)

    def __post_init__(self) -> None:
        super().__post_init__()
        self.reset(0)

    def reset(self, num_vehicles: int) -> None:
        """Clear the speed history and the previous command for ``num_vehicles`` vehicles."""
        self._n = int(num_vehicles)
        self._history: FloatArray = np.zeros((0, self._n))
        self._count = 0
        self._next = 0
        self.v_cmd: FloatArray = np.zeros(self._n)

    def _remember(self, speed: FloatArray, dt: float) -> FloatArray:
        """Add this step's speeds to the ring buffer; return the mean over it (m/s)."""
        if self._history.shape[0] == 0:
            window = max(1, round(self.history_time / dt) - 1)
            self._history = np.zeros((window, self._n))
        self._history[self._next] = speed
        self._next = (self._next + 1) % self._history.shape[0]
        self._count = min(self._count + 1, self._history.shape[0])
        return np.asarray(self._history[: self._count].mean(axis=0), dtype=np.float64)

    def _accel(self, inputs: CarFollowingInputs) -> FloatArray:
        if inputs.size != self._n:
            self.reset(inputs.size)
        u_mean = self._remember(inputs.speed, inputs.dt)
        self.v_cmd = pi_saturation_speed(
            inputs.speed, inputs.headway, inputs.leader_speed, u_mean, self.v_cmd,
            v_catch=self.v_catch, g_l=self.g_l, g_u=self.g_u, gamma=self.gamma,
        )  # fmt: skip
        accel = (self.v_cmd - inputs.speed) / inputs.dt
        if inputs.max_accel is not None:
            accel = np.minimum(accel, inputs.max_accel)
        return accel
