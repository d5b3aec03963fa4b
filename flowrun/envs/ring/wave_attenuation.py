"""Stabilizing the ring (Wu et al., "Flow", T-RO 2021): one AV dissolves the stop-and-go wave.

At every reset the ring length is redrawn as an integer in ``ring_length`` metres (Flow draws
``randint(low, high)``), so the policy must work across densities.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.rewards import wave_attenuation_terms
from flowrun.envs.ring.accel import RingAccelBase
from flowrun.envs.ring.tasks import (
    V_OBS_SCALE,
    RingBatch,
    RingTask,
    WavePOTask,
    partial_observation,
    po_observation,
)
from flowrun.errors import ConfigError
from flowrun.networks.base import Network

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AV, m/s^2
    "max_accel": 1,
    # maximum deceleration of the AV, m/s^2
    "max_decel": 1,
    # range the ring length is drawn from at each reset, m (null: keep the network's length)
    "ring_length": [220, 270],
}

def v_eq_max_function(v: Any, *args: float) -> Any:
    """Flow's residual for the ring's equilibrium speed with one AV (solve it for ``v``).

    ``args`` = (number of vehicles, ring length m). The largest equilibrium gap with one AV,
    ``(length - 5 n) / (n - 1)``, minus IDM's equilibrium gap at speed ``v`` (v0 = 30 m/s,
    s0 = 2 m, T = 1 s, delta = 4): ``(s0 + v T) / sqrt(1 - (v / v0)^delta)``. ``v`` may be
    a number or an array (``scipy.optimize.fsolve`` passes one).
    """
    num_vehicles, length = args
    s_eq_max = (length - num_vehicles * 5.0) / (num_vehicles - 1)
    return s_eq_max - (2.0 + v * 1.0) * (1.0 - (v / 30.0) ** 4) ** -0.5


def ring_bounds(additional_params: dict[str, Any]) -> tuple[int, int] | None:
    """``(low, high)`` of the ring length drawn at each reset (m), or ``None`` to keep it.

    Raises:
        ConfigError: ``ring_length`` is not ``[low, high]`` with ``0 < low <= high``.
    """
    given = additional_params["ring_length"]
    if given is None:
        return None
    try:
        low, high = given
        ok = 0 < low <= high
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ConfigError(
            f"expected [low, high] with 0 < low <= high (metres) or null, got {given!r}",
            path="env.additional_params.ring_length",
        )
    return int(low), int(high)


def spread_lengths(bounds: tuple[int, int], episodes: int) -> list[int]:
    """Ring lengths (m) spreading ``episodes`` evaluation episodes evenly over ``bounds``:
    the midpoints of ``episodes`` equal slices, rounded half up to whole metres (228, 245 and
    262 m for 3 episodes over [220, 270])."""
    low, high = bounds
    return [int(low + (high - low) * (i + 0.5) / episodes + 0.5) for i in range(episodes)]


class WaveAttenuationEnv(RingAccelBase):
    """Fully observed ring with a redrawn length (Flow's ``WaveAttenuationEnv``).

    Observation: speeds / max speed and positions / length of all cars (``2 * N`` in [0, 1]).
    Action: acceleration of each RL car in ``[-max_decel, max_accel]`` m/s^2.
    Reward: ``4 * mean(v) / 20 - 4 * mean(|a|)`` (terms in ``info["reward_terms"]``);
    mean speed in evaluate mode; 0 after a collision and when no action is given (warm-up).
    """

    DEFAULT_EXPERIMENT = "envs/ring.yaml"

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._chosen_length: float | None = None  # set by reset(options=...)
        super().__init__(*args, **kwargs)
        self.ring_range()  # a bad ring_length fails here, not at the first reset

    def ring_range(self) -> tuple[int, int] | None:
        """``(low, high)`` of the ring length draw, m; ``None`` keeps the network's length."""
        return ring_bounds(self.env_params.additional_params)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """As :meth:`Env.reset`; ``options={"ring_length": L}`` sets this episode's length (m).

        The length is still drawn first, so every other random draw of the episode is the
        one a reset with the same seed and no options makes.
        """
        chosen = (options or {}).get("ring_length")
        if chosen is not None and not (isinstance(chosen, int | float) and chosen > 0):
            raise ConfigError(f"reset option ring_length must be a length > 0 m, got {chosen!r}")
        self._chosen_length = None if chosen is None else float(chosen)
        return super().reset(seed=seed, options=options)

    def evaluation_options(self, episodes: int) -> list[dict[str, Any]]:
        """Reset options that spread ``episodes`` evaluation episodes evenly over the ring lengths.

        The midpoints of ``episodes`` equal slices of ``ring_length``, rounded half up to whole
        metres (228, 245 and 262 m for 3 episodes over [220, 270]): an evaluation covers the
        short, dense rings and the long ones alike.
        """
        bounds = self.ring_range()
        if bounds is None:
            return [{} for _ in range(episodes)]
        return [{"ring_length": length} for length in spread_lengths(bounds, episodes)]

    def episode_network(self) -> Network:
        """The ring with a length drawn uniformly from the integers in ``ring_length`` (or the
        length given to :meth:`reset` in ``options``)."""
        bounds = self.ring_range()
        drawn = None if bounds is None else int(self.np_random.integers(bounds[0], bounds[1] + 1))
        length = self._chosen_length if self._chosen_length is not None else drawn
        if length is None:
            return self.initial_network
        return self.initial_network.with_params(length=length)

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Speed reward minus acceleration penalty (mean speed when evaluating).

        0 when ``rl_actions`` is ``None`` (warm-up steps, or a rollout without a policy),
        before the evaluate check, as in Flow.
        """
        if rl_actions is None:
            self.reward_terms = {"speed": 0.0, "accel_penalty": 0.0}
            return 0.0
        speeds = self.k.vehicle.speed
        if self.env_params.evaluate:
            return float(np.mean(speeds))
        actions = None if rl_actions is None else np.asarray(rl_actions, dtype=np.float64)
        self.reward_terms = wave_attenuation_terms(speeds, actions, bool(kwargs.get("fail")))
        return float(sum(self.reward_terms.values()))


class WaveAttenuationPOEnv(WaveAttenuationEnv):
    """Partially observed ring (Flow's ``WaveAttenuationPOEnv``): the AV sees itself and its leader.

    Observation (3 values): AV speed / 15, (leader speed - AV speed) / 15, and the gap to the
    leader's front bumper ``(x_lead - x_av) mod L`` divided by the largest ring length (the
    ring's own length when ``ring_length`` is null).
    Action, reward, termination: as :class:`WaveAttenuationEnv` (one RL car expected).
    """

    RING_TASK: ClassVar[type[RingTask]] = WavePOTask

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """Three unbounded values (see the class docstring)."""
        return Box(low=-np.inf, high=np.inf, shape=(3,), dtype=np.float32)

    def get_state(self) -> Any:
        """AV speed, relative leader speed and distance, normalised."""
        vk = self.k.vehicle
        rl_ids = vk.get_rl_ids()
        if not rl_ids:
            return np.zeros(3)
        bounds = self.ring_range()
        max_length = float(bounds[1]) if bounds is not None else self.k.network.length()
        length = self.k.network.length()
        ring = RingBatch(vk.speed[:, None], vk.position[:, None], length, vk.leader)  # one ring
        return po_observation(ring, vk.table.row(rl_ids[0]), max_length)[:, 0]


__all__ = [
    "V_OBS_SCALE", "WaveAttenuationEnv", "WaveAttenuationPOEnv", "partial_observation",
    "ring_bounds", "spread_lengths", "v_eq_max_function",
]  # fmt: skip
