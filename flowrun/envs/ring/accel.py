"""``AccelEnv``: a central agent sets the acceleration of every RL car; all cars observed.

Flow's ``flow.envs.ring.accel``. Works on any network with a fixed number of cars (ring,
figure eight, ...): Flow's figureeight0/1/2 benchmarks run it on the figure eight.
"""

from __future__ import annotations

from functools import cached_property
from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.base import Env
from flowrun.envs.rewards import desired_velocity
from flowrun.envs.ring.tasks import (
    AccelTask,
    RingActions,
    RingTask,
    WaveTask,
    acceleration_box,
    clip_unit,
    full_observation,
)
from flowrun.flow_values import FLOW_ERROR
from flowrun.types import IntArray

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the RL cars, m/s^2
    "max_accel": 3,
    # maximum deceleration of the RL cars, m/s^2
    "max_decel": 3,
    # desired speed of all cars, m/s (the reward's target)
    "target_velocity": 10,
    # observe and command cars sorted by absolute position instead of in id order
    "sort_vehicles": False,
}


def fit(values: np.ndarray, size: int) -> np.ndarray:
    """``values`` cut or zero-padded to ``size`` entries (a fixed-size observation part)."""
    if values.size == size:
        return values
    out = np.zeros(size)
    n = min(size, values.size)
    out[:n] = values[:n]
    return out


def from_first_rl(pos: np.ndarray, is_rl: np.ndarray, length: float) -> np.ndarray:
    """Positions measured forward from the first RL car, modulo ``length``; that car's own
    entry keeps its position. Unchanged when there is no RL car."""
    rl = np.flatnonzero(is_rl)
    return from_entry(pos, int(rl[0]), length) if rl.size else pos


def from_entry(pos: np.ndarray, i: int, length: Any) -> np.ndarray:
    """Positions measured forward from entry ``i``'s, modulo ``length`` (a float, or a 0-d
    array: a ufunc converts a Python float at every call); entry ``i`` keeps its own
    position."""
    own = pos[i]
    out = np.mod(pos - own, length)
    out[i] = own
    return out


class AbsolutePositions:
    """Flow's ``absolute_position`` bookkeeping, over the kernel's vehicle rows.

    At the start of an episode a car's absolute position is its position ``x``
    (``get_x_by_id``); each update adds the change of ``x`` since the last update and takes
    the result modulo the network length ``L``. A car that enters later starts at ``x mod L``.
    On a ring this is ``x`` itself; on the figure eight it is the distance driven, wrapped.

    The updates are kept and summed up when the value is first read (the same additions in
    the same order), so a run that never reads it pays a copy of ``x`` per step.
    """

    #: at most this many positions (cars x updates) wait to be summed up (8 MB)
    PENDING = 1_000_000

    def __init__(self) -> None:
        self.table: Any = None
        self.version = -1
        self.ids: list[str] = []
        self._value = np.zeros(0)
        self._prev = np.zeros(0)
        self._pending: list[np.ndarray] = []
        self._length = 0.0

    @property
    def value(self) -> np.ndarray:
        """Each row's absolute position, m."""
        self._fold()
        return self._value

    def _fold(self) -> None:
        """Apply the waiting updates, in order."""
        if not self._pending:
            return
        value, prev, length = self._value, self._prev, self._length
        for x in self._pending:
            value = np.mod(value + (x - prev), length)
            prev = x
        self._value, self._prev = value, prev
        self._pending = []

    def current(self, vk: Any) -> bool:
        """Whether the bookkeeping is of the kernel's present population."""
        table = getattr(vk, "table", None)
        return table is not None and table is self.table and table.version == self.version

    def start(self, vk: Any) -> None:
        """Absolute positions = positions now (Flow, at reset)."""
        self.table, self.version = vk.table, vk.table.version
        self.ids = list(vk.table.ids)
        self._prev = np.array(vk.position, dtype=np.float64)
        self._value = self._prev.copy()
        self._pending = []

    def _follow(self, vk: Any, length: float) -> None:
        """Realign the rows after cars entered or left (newcomers start at ``x mod L``)."""
        self._fold()
        known = dict(zip(self.ids, zip(self._value.tolist(), self._prev.tolist(), strict=True),
                         strict=True))  # fmt: skip
        x = np.asarray(vk.position, dtype=np.float64)
        ids = list(vk.table.ids)
        pairs = [known.get(v, (xi % length, xi)) for v, xi in zip(ids, x.tolist(), strict=True)]
        self._value = np.array([p[0] for p in pairs], dtype=np.float64)
        self._prev = np.array([p[1] for p in pairs], dtype=np.float64)
        self.table, self.version, self.ids = vk.table, vk.table.version, ids

    def update(self, vk: Any, length: float) -> None:
        """Add each car's change of position since the last update, modulo ``length``."""
        if vk.table is not self.table:
            self.start(vk)
        elif vk.table.version != self.version:
            self._follow(vk, length)
        x = np.array(vk.position, dtype=np.float64)
        if length != self._length or (len(self._pending) + 1) * x.size > self.PENDING:
            self._fold()
            self._length = length
        self._pending.append(x)

    def of_rows(self, vk: Any) -> np.ndarray:
        """Absolute position of each row of the kernel (``x`` where not bookkept yet)."""
        if not self.current(vk):
            return np.asarray(vk.position, dtype=np.float64)
        return self.value


class RingAccelBase(Env):
    """What the fully observed ring tasks share (``AccelEnv``, ``WaveAttenuationEnv``).

    Observation: ``2 * num_vehicles`` values in [0, 1]: speeds / max speed, then positions /
    network length, ordered by id (or by position when ``sort_vehicles`` is set).
    Action: one acceleration per RL car in ``[-max_decel, max_accel]`` m/s^2.
    """

    #: the task's definition over a batch of rings (:mod:`flowrun.envs.ring.tasks`)
    RING_TASK: ClassVar[type[RingTask]] = WaveTask

    @property
    def action_space(self) -> Box:  # type: ignore[override]
        """One acceleration per RL vehicle (the ring task's, :attr:`ring_actions`)."""
        return self.ring_actions.space

    @cached_property
    def ring_actions(self) -> RingActions:
        """The ring task's actions: bounds from ``additional_params``, one per RL car placed
        at the start."""
        return RingActions(
            self.env_params.additional_params, self.initial_vehicles.num_rl_vehicles
        )

    def clip_actions(self, rl_actions: Any) -> Any:
        """The ring task's action handling for a batch of one ring
        (:meth:`RingActions.accelerations`): the RL cars' accelerations, m/s^2, clipped to
        the action space when ``env_params.clip_actions``. A subclass with an action space
        of its own (:class:`LaneChangeAccelEnv`) keeps :meth:`Env.clip_actions`."""
        if self._spaces()[0] is not self.ring_actions.space:
            return super().clip_actions(rl_actions)
        return self.ring_actions.of_one(rl_actions, self.env_params.clip_actions)

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """Normalised speeds and positions of all vehicles."""
        return Box(
            low=0.0, high=1.0, shape=(2 * self.initial_vehicles.num_vehicles,), dtype=np.float32
        )

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        rl_ids = self.k.vehicle.get_rl_ids()
        self.k.vehicle.apply_acceleration(rl_ids, rl_actions)

    def get_state(self) -> Any:
        """Speeds / max speed and positions / length, in [0, 1]."""
        vk = self.k.vehicle
        speed, pos = vk.speed, vk.position
        if self.env_params.additional_params.get("sort_vehicles"):
            order = np.argsort(pos, kind="stable")
            speed, pos = speed[order], pos[order]
        return full_observation(speed, pos, self.k.network.max_speed(), self.k.network.length())


class AccelEnv(RingAccelBase):
    """Fully observed network with accelerations for the RL cars (Flow's ``AccelEnv``).

    Made for networks whose cars stay (ring, figure eight); the observation keeps its size
    if cars come or go (zero-padded or cut to the initial count).

    Observation: ``2 * num_vehicles`` values in [0, 1]: speeds / the network's max speed,
    then positions ``get_x_by_id`` / network length, in :attr:`sorted_ids` order. With
    ``relative_positions: true`` in ``additional_params`` (flowrun's option; Flow has only
    absolute positions) each position but the first RL car's is measured forward from that
    car, modulo the length, so its distance to any car ahead is one entry that never jumps
    when a car passes the network's start; the RL car's own entry stays absolute.
    Action: one acceleration per RL car in ``[-max_decel, max_accel]`` m/s^2, in
    :attr:`sorted_ids` order (extra actions are ignored when fewer RL cars are present).
    Reward: :func:`~flowrun.envs.rewards.desired_velocity` towards ``target_velocity``
    (0 after a collision); the mean speed in evaluate mode.
    Termination: collision; truncation: horizon.
    """

    DEFAULT_EXPERIMENT = "envs/ring.yaml"

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS
    OPTIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = {"relative_positions": False}
    RING_TASK: ClassVar[type[RingTask]] = AccelTask

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._positions = AbsolutePositions()
        self._observed_version: tuple[Any, int] | None = None
        #: (the population and its version, the RL cars' rows then), when not sorting
        self._rl_cache: tuple[tuple[Any, int], IntArray] | None = None
        #: the observed cars' count (the initial vehicles'), found at the first observation
        self._num_observed: int | None = None
        #: ((cars, max speed, length), the observation's divisors, the length as a 0-d array)
        self._obs_scale: tuple[tuple[int, float, float], np.ndarray, np.ndarray] | None = None
        super().__init__(*args, **kwargs)
        self._from_rl = bool(self.env_params.additional_params.get("relative_positions"))
        self._sorting = bool(self.env_params.additional_params.get("sort_vehicles"))

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start a new episode; absolute positions restart at the positions (Flow)."""
        obs, info = super().reset(seed=seed, options=options)
        self._positions.start(self.k.vehicle)
        if self._sorting:
            obs = self._format_obs(self.get_state())
        return obs, info

    # ------------------------------------------------------------------ Flow's bookkeeping
    @property
    def absolute_position(self) -> dict[str, float]:
        """Flow's ``absolute_position``: each car's start position plus the distance it
        drove, modulo the network length (m), updated every simulation step (before SUMO
        moves the cars, as Flow's ``additional_command``). Before any bookkeeping of this
        episode: ``get_x_by_id`` modulo the length."""
        vk = self.k.vehicle
        positions: AbsolutePositions | None = getattr(self, "_positions", None)
        if positions is not None and positions.current(vk):
            return dict(zip(positions.ids, positions.value.tolist(), strict=True))
        length = self.k.network.length()
        return {veh_id: float(vk.get_x_by_id(veh_id)) % length for veh_id in vk.get_ids()}

    def _get_abs_position(self, veh_id: str) -> float:
        """Flow's helper: :attr:`absolute_position` of one car (m; -1001 if unknown)."""
        vk = self.k.vehicle
        positions: AbsolutePositions | None = getattr(self, "_positions", None)
        if positions is not None and positions.current(vk):
            if veh_id not in vk.table:
                return FLOW_ERROR
            return float(positions.value[vk.table.row(veh_id)])
        return float(vk.get_x_by_id(veh_id)) % self.k.network.length()

    @property
    def sorted_ids(self) -> list[str]:
        """Vehicle ids in observation order (Flow's property): by absolute position when
        ``sort_vehicles`` is set, else as ``get_ids()``."""
        ids = self.k.vehicle.get_ids()
        if self.env_params.additional_params.get("sort_vehicles"):
            return sorted(ids, key=self._get_abs_position)
        return list(ids)

    def _order(self) -> np.ndarray | slice:
        """Kernel rows in :attr:`sorted_ids` order."""
        if not self._sorting:
            return slice(None)
        return np.argsort(self._positions.of_rows(self.k.vehicle), kind="stable")

    def additional_command(self) -> None:
        """Flow's: mark the human cars observed when RL cars drive, and update
        :attr:`absolute_position`."""
        vk = self.k.vehicle
        key = (vk.table, vk.table.version)
        if key != self._observed_version:
            self._observed_version = key
            if vk.num_rl_vehicles > 0:
                for veh_id in vk.get_human_ids():
                    vk.set_observed(veh_id)
        # on a ring the absolute position is the ring position itself, so the bookkeeping is
        # only kept where it differs (other networks) or orders the observation
        if self._sorting or not self.network.spec.closed:
            self._positions.update(vk, self.k.network.length())

    # ------------------------------------------------------------------ Flow's hooks
    def _rl_rows(self) -> IntArray:
        """The RL cars' kernel rows in :attr:`sorted_ids` order (kept while the rows are)."""
        vk = self.k.vehicle
        table = vk.table
        if self._sorting:
            rows = np.argsort(self._positions.of_rows(vk), kind="stable")
            return rows[table.is_rl[rows]]
        key = (table, table.version)
        if self._rl_cache is None or self._rl_cache[0] != key:
            self._rl_cache = (key, table.is_rl.nonzero()[0])
        return self._rl_cache[1]

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        rows = self._rl_rows()
        actions = np.asarray(rl_actions, dtype=np.float64)
        if actions.ndim != 1:
            actions = actions.reshape(-1)
        n = min(rows.size, actions.size)
        if n == rows.size == actions.size:  # (the common case: no slicing)
            self.k.vehicle.apply_acceleration_rows(rows, actions)
        elif n:
            self.k.vehicle.apply_acceleration_rows(rows[:n], actions[:n])

    def get_state(self) -> Any:
        """Speeds / max speed, then positions / length, in :attr:`sorted_ids` order, in [0, 1]."""
        vk = self.k.vehicle
        n = self._num_observed
        if n is None:
            n = self._num_observed = self.initial_vehicles.num_vehicles
        speed, pos = vk.speed, vk.position
        if self._sorting:
            order = self._order()
            speed, pos = speed[order], pos[order]
            if self._from_rl:
                pos = from_first_rl(pos, vk.table.is_rl[order], self.k.network.length())
        # full_observation's divisions as one: each value over its own divisor
        scale = (n, self.k.network.max_speed(), self.k.network.length())
        if self._obs_scale is None or self._obs_scale[0] != scale:
            self._obs_scale = (scale, np.repeat([scale[1], scale[2]], n), np.array(scale[2]))
        if self._from_rl and not self._sorting:  # (in row order: the first RL row, kept)
            rl = self._rl_rows()
            pos = from_entry(pos, int(rl[0]), self._obs_scale[2]) if rl.size else pos
        if speed.size != n:  # (cars came or went: cut or zero-padded)
            speed, pos = fit(speed, n), fit(pos, n)
        return clip_unit(np.concatenate((speed, pos)) / self._obs_scale[1])

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Desired-velocity reward (mean speed when ``env_params.evaluate``)."""
        return desired_velocity_reward(self, bool(kwargs.get("fail", False)))


def desired_velocity_reward(env: Env, fail: bool) -> float:
    """Flow's desired-velocity reward of ``env`` towards its ``target_velocity`` (0 after a
    collision; the mean speed when ``env_params.evaluate``); sets ``env.reward_terms``."""
    speeds = env.k.vehicle.speed
    if env.env_params.evaluate:
        return float(np.mean(speeds)) if speeds.size else 0.0
    reward = desired_velocity(
        speeds, float(env.env_params.additional_params["target_velocity"]), fail=fail
    )
    env.reward_terms = {"desired_velocity": reward}
    return reward


__all__ = [
    "ADDITIONAL_ENV_PARAMS", "AbsolutePositions", "AccelEnv", "RingAccelBase",
    "acceleration_box", "clip_unit", "desired_velocity_reward", "fit", "from_entry",
    "from_first_rl",
]  # fmt: skip
