"""Velocity controllers from Stern et al. (2018), "Dissipation of stop-and-go waves via control
of autonomous vehicles: Field experiments" (https://arxiv.org/abs/1705.01693).

Both compute a commanded speed ``v_cmd`` (m/s) and turn it into the acceleration that reaches
it in one step, ``(v_cmd - v)/dt`` (m/s^2).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from flowrun.controllers._checks import number
from flowrun.controllers.base import AccelerationController
from flowrun.types import CarFollowingInputs, FloatArray


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


class FollowerStopper(AccelerationController):
    """Stern et al.'s FollowerStopper (see :func:`follower_stopper_speed`).

    Args:
        veh_id: Flow's vehicle id (Flow passes it first).
        car_following_params: the vehicle type's ``SumoCarFollowingParams`` (its
            ``accel``/``decel`` cap the command when the kernel gives no limits).
        v_des: desired speed, m/s.
        danger_edges: edges near which Flow hands the car back to SUMO (kept for the
            kernel; the formula itself does not know edges).
        control_length: ``(x_start, x_end)`` in m outside which Flow hands the car to SUMO
            (kept for the kernel, as ``danger_edges``).
        dx_1_0, dx_2_0, dx_3_0: base switching gaps, m. d_1, d_2, d_3: decelerations, m/s^2.
        noise: acceleration noise, as for every controller.
        fail_safe: Flow's FollowerStopper always runs ``safe_velocity``; so does the default.

    The command is clipped to ``[-max_decel, max_accel]``, the vehicle type's limits (Flow
    clips to the vehicle type's accel/decel), when they are known.
    """

    registered_name = "FollowerStopper"

    def __init__(
        self,
        veh_id: str | None = None,
        car_following_params: Any = None,
        v_des: float = 15,
        danger_edges: Sequence[str] | None = None,
        control_length: Sequence[float] | None = None,
        dx_1_0: float = 4.5,
        dx_2_0: float = 5.25,
        dx_3_0: float = 6.0,
        d_1: float = 1.5,
        d_2: float = 1.0,
        d_3: float = 0.5,
        noise: float = 0,
        fail_safe: str | Sequence[str] | None = "safe_velocity",
        display_warnings: bool = True,
    ) -> None:
        super().__init__(
            noise=noise, fail_safe=fail_safe, veh_id=veh_id,
            car_following_params=car_following_params, display_warnings=display_warnings,
        )  # fmt: skip
        me = type(self).__name__
        self.v_des = number(me, "v_des", v_des, low=0)
        self.dx_1_0 = number(me, "dx_1_0", dx_1_0, low=0)
        self.dx_2_0 = number(me, "dx_2_0", dx_2_0, low=self.dx_1_0, strict=True)
        self.dx_3_0 = number(me, "dx_3_0", dx_3_0, low=self.dx_2_0, strict=True)
        self.d_1 = number(me, "d_1", d_1, low=0, strict=True)
        self.d_2 = number(me, "d_2", d_2, low=0, strict=True)
        self.d_3 = number(me, "d_3", d_3, low=0, strict=True)
        self.danger_edges: frozenset[str] = frozenset(danger_edges or ())
        self.control_length: tuple[float, float] | None = None
        if control_length is not None:
            lo, hi = (number(me, "control_length", x) for x in control_length)
            self.control_length = (lo, hi)

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

    Args:
        veh_id: Flow's vehicle id (Flow passes it first).
        car_following_params: the vehicle type's ``SumoCarFollowingParams``.
        v_catch: catch-up speed added to ``U`` at large gaps, m/s.
        g_l, g_u: gaps (m) between which the catch-up speed ramps in.
        gamma: gap width (m) over which the controller blends from the leader's speed.
        history_time: length of the speed history, s.
    """

    registered_name = "PISaturation"
    stateful = True

    def __init__(
        self,
        veh_id: str | None = None,
        car_following_params: Any = None,
        v_catch: float = 1,
        g_l: float = 7,
        g_u: float = 30,
        gamma: float = 2,
        history_time: float = 38,
        noise: float = 0,
        fail_safe: str | Sequence[str] | None = None,
        display_warnings: bool = True,
    ) -> None:
        super().__init__(
            noise=noise, fail_safe=fail_safe, veh_id=veh_id,
            car_following_params=car_following_params, display_warnings=display_warnings,
        )  # fmt: skip
        me = type(self).__name__
        self.v_catch = number(me, "v_catch", v_catch, low=0)
        self.g_l = number(me, "g_l", g_l, low=0)
        self.g_u = number(me, "g_u", g_u, low=self.g_l, strict=True)
        self.gamma = number(me, "gamma", gamma, low=0, strict=True)
        self.history_time = number(me, "history_time", history_time, low=0, strict=True)
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
