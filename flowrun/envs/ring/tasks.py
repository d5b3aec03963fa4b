"""The ring tasks as pure array functions over a batch of ring states.

One definition of each task's observation, reward and actions: the SUMO envs
(:mod:`flowrun.envs.ring.accel`, :mod:`flowrun.envs.ring.wave_attenuation`) call it with a
batch of one ring (their kernel's step), the numpy backend (:mod:`flowrun.fastring`) with
``B`` rings. Each env class names its task (``RING_TASK``); a task is made from the env's
``additional_params`` and the facts of its network.

Arrays of a batch are ``(N, B)``: ``N`` cars (rows, in id order), one column per ring.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.controllers.car_following_formulas import ONE, ZERO
from flowrun.envs.rewards import desired_velocities, wave_attenuation_rewards
from flowrun.types import BoolArray, FloatArray, IntArray

V_OBS_SCALE = 15.0  # m/s: speeds in the partial observation are divided by this


@dataclass(eq=False)
class RingBatch:
    """``B`` rings' state as a ring task sees it.

    Attributes:
        speed: every car's speed, m/s, ``(N, B)``.
        distance: every car's position along its ring, m, ``(N, B)``, before it is taken
            modulo the ring length (a position already in ``[0, length)`` works too).
        length: every ring's length, m, ``(B,)`` (or a number for a batch of one).
        leader: the row of every car's leader on its ring, ``(N, B)`` (-1: none), or
            ``(N,)`` when every ring has the same order.
    """

    speed: FloatArray
    distance: FloatArray
    length: FloatArray | float
    leader: IntArray

    @cached_property
    def position(self) -> FloatArray:
        """Every car's position on its ring, m, ``(N, B)``."""
        return np.mod(self.distance, self.length)

    def leader_of(self, row: int) -> int | tuple[IntArray, IntArray]:
        """Where the leader of car ``row`` is on every ring (the car itself where it has
        none), as an index into an ``(N, B)`` array: a row when every ring has the same
        order, else (rows, columns)."""
        lead = self.leader[row]
        if lead.ndim == 0:  # every ring has the same order: a whole row
            return int(lead) if lead >= 0 else row
        return np.where(lead >= 0, lead, row), np.arange(lead.shape[0])


def clip_unit(x: FloatArray) -> FloatArray:
    """``x`` clipped to [0, 1] in place (two ufuncs with 0-d array bounds: cheaper than
    ``np.clip`` per step, and than Python floats, which a ufunc converts at every call)."""
    np.maximum(x, ZERO, out=x)
    return np.minimum(x, ONE, out=x)


def full_observation(
    speed: FloatArray, position: FloatArray, max_speed: float, length: Any
) -> FloatArray:
    """Speeds / the network's max speed, then positions / its length, clipped to [0, 1]:
    ``(2N, B)`` for ``(N, B)`` inputs (``(2N,)`` for one ring's ``(N,)``)."""
    return clip_unit(np.concatenate([speed / max_speed, position / length]))


def partial_observation(v_av: Any, v_lead: Any, gap: Any, max_length: float) -> FloatArray:
    """The AV's view in ``WaveAttenuationPOEnv``: ``[v_av/15, (v_lead - v_av)/15,
    gap/max_length]`` (speeds in m/s, gap to the leader's front bumper and length in m).

    Scalars give a vector of 3; arrays of ``B`` rings give ``(3, B)``.
    """
    return np.array([v_av / V_OBS_SCALE, (v_lead - v_av) / V_OBS_SCALE, gap / max_length])


def po_observation(rings: RingBatch, av: int, max_length: float) -> FloatArray:
    """The AV's view in ``WaveAttenuationPOEnv`` on every ring, ``(3, B)``: its speed / 15,
    (leader speed - its speed) / 15 and the gap to the leader's front bumper
    ``(x_lead - x_av) mod L`` / ``max_length`` (:func:`partial_observation`).

    Args:
        rings: the rings. av: the AV's row. max_length: the largest ring length, m.
    """
    length, lead = rings.length, rings.leader_of(av)
    x_av = np.mod(rings.distance[av], length)
    gap = np.mod(np.mod(rings.distance[lead], length) - x_av, length)
    return partial_observation(rings.speed[av], rings.speed[lead], gap, max_length)


def acceleration_box(additional_params: dict[str, Any], num_rl: int) -> Box:
    """One acceleration per RL car in ``[-|max_decel|, max_accel]`` m/s^2."""
    return Box(
        low=-abs(float(additional_params["max_decel"])),
        high=float(additional_params["max_accel"]),
        shape=(num_rl,),
        dtype=np.float32,
    )


def clip_few(values: list[float], bounds: list[tuple[float, float]]) -> FloatArray:
    """``np.minimum(np.maximum(values, low), high)`` on Python floats, for few values (the
    same floats: a NaN stays NaN), as a float64 array; ``bounds``: (low, high) of each."""
    pairs = zip(values, bounds, strict=True)
    return np.array([lo if x < lo else (hi if x > hi else x) for x, (lo, hi) in pairs], np.float64)


class RingActions:
    """A ring task's actions: one acceleration per RL car in ``[-|max_decel|, max_accel]``
    m/s^2 (:func:`acceleration_box`).

    Args:
        additional_params: the env's ``additional_params``.
        num_rl: RL cars per ring.
    """

    #: up to this many RL cars, :meth:`of_one` clips on Python floats (numpy's cost is per call)
    FEW = 16

    def __init__(self, additional_params: dict[str, Any], num_rl: int) -> None:
        self.space = acceleration_box(additional_params, num_rl)
        self.low = np.asarray(self.space.low, dtype=np.float64)
        self.high = np.asarray(self.space.high, dtype=np.float64)
        self._bounds = list(zip(self.low.tolist(), self.high.tolist(), strict=True))

    def accelerations(self, actions: Any, clip: bool) -> FloatArray:
        """Actions ``(B, num_rl)`` as the RL cars' accelerations ``(num_rl, B)``, m/s^2,
        clipped to the action space when ``clip`` (``env.clip_actions``)."""
        b = np.shape(actions)[0]
        if self.low.size == 0:
            return np.zeros((0, b))
        a = np.asarray(actions, dtype=np.float64).reshape(-1, self.low.size)
        if clip:
            a = np.minimum(np.maximum(a, self.low), self.high)
        return np.ascontiguousarray(a.T)

    def of_one(self, actions: Any, clip: bool) -> FloatArray:
        """:meth:`accelerations` of one ring's actions, ``(num_rl,)`` (the same values in
        fewer numpy calls: an env step's share)."""
        n = self.low.size
        if n == 0:
            return np.zeros(0)
        few = n <= self.FEW and isinstance(actions, np.ndarray) and actions.shape == (n,)
        if clip and few and actions.dtype.kind == "f":
            return clip_few(actions.tolist(), self._bounds)
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != self.low.shape:
            a = a.reshape(-1, n)[0]
        return np.minimum(np.maximum(a, self.low), self.high) if clip else a


class RingTask:
    """A ring task: its spaces, and its actions, observation and reward of a batch of rings.

    Args:
        additional_params: the env's ``additional_params``.
        num_cars: cars per ring; rl_rows: rows of the RL cars (id order).
        max_speed: the network's largest speed limit, m/s.
        max_length: the largest ring length an episode can have, m.
        evaluate: ``env.evaluate`` (the reward is then every ring's mean speed).
    """

    def __init__(self, additional_params: dict[str, Any], num_cars: int, rl_rows: IntArray,
                 max_speed: float, max_length: float, evaluate: bool) -> None:  # fmt: skip
        self.params = additional_params
        self.num_cars, self.rl_rows = num_cars, rl_rows
        self.max_speed, self.max_length, self.evaluate = max_speed, max_length, evaluate
        self.actions = RingActions(additional_params, int(rl_rows.size))
        self.action_space = self.actions.space

    @property
    def observation_space(self) -> Box:
        """Speeds / max speed and positions / length of all cars (``2 * N`` in [0, 1])."""
        return Box(low=0.0, high=1.0, shape=(2 * self.num_cars,), dtype=np.float32)

    def accelerations(self, actions: Any, clip: bool) -> FloatArray:
        """:meth:`RingActions.accelerations`: ``(B, num_rl)`` -> ``(num_rl, B)``, m/s^2."""
        return self.actions.accelerations(actions, clip)

    def observe(self, rings: RingBatch) -> FloatArray:
        """Every ring's observation, ``(obs_dim, B)``."""
        return full_observation(rings.speed, rings.position, self.max_speed, rings.length)

    def rewards(self, rings: RingBatch, accel: FloatArray, crashed: BoolArray) -> FloatArray:
        """Every ring's reward for the step just taken (``accel``: the RL cars'
        accelerations as applied, ``(num_rl, B)``), ``(B,)``."""
        raise NotImplementedError


class AccelTask(RingTask):
    """``AccelEnv``: all cars observed; desired-velocity reward towards ``target_velocity``."""

    def rewards(self, rings: RingBatch, accel: FloatArray, crashed: BoolArray) -> FloatArray:
        """Desired velocity (0 after a collision); the mean speed when evaluating."""
        if self.evaluate:
            return np.asarray(rings.speed.mean(axis=0), dtype=np.float64)
        return desired_velocities(rings.speed, float(self.params["target_velocity"]), crashed)


class WaveTask(RingTask):
    """``WaveAttenuationEnv``: all cars observed; ``4 mean(v) / 20 - 4 mean(|a|)``."""

    def rewards(self, rings: RingBatch, accel: FloatArray, crashed: BoolArray) -> FloatArray:
        """Speed term minus acceleration penalty (0 after a collision); the mean speed
        when evaluating. The SUMO env's terms (``wave_attenuation_terms``) are the same
        formula for a batch of one."""
        if self.evaluate:
            return np.asarray(rings.speed.mean(axis=0), dtype=np.float64)
        return wave_attenuation_rewards(rings.speed, accel, crashed)


class WavePOTask(WaveTask):
    """``WaveAttenuationPOEnv``: the first RL car sees itself and its leader."""

    OBS_DIM: ClassVar[int] = 3

    @property
    def observation_space(self) -> Box:
        """Three unbounded values (see :meth:`observe`)."""
        return Box(low=-np.inf, high=np.inf, shape=(self.OBS_DIM,), dtype=np.float32)

    def observe(self, rings: RingBatch) -> FloatArray:
        """:func:`po_observation` of the first RL car, ``(3, B)``; zeros without one."""
        if not self.rl_rows.size:
            return np.zeros((self.OBS_DIM, np.shape(rings.speed)[1]))
        return po_observation(rings, int(self.rl_rows[0]), self.max_length)
