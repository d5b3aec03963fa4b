"""The ring envs' spaces, observations and rewards for many rings at once.

The same formulas as the SUMO envs (:mod:`flowrun.envs.ring`): the partial observation of
:class:`~flowrun.envs.ring.wave_attenuation.WaveAttenuationPOEnv`
(:func:`~flowrun.envs.ring.wave_attenuation.partial_observation`), the full observation of
``WaveAttenuationEnv``/``AccelEnv`` (speeds / max speed, positions / length, in id order), and
the rewards of :mod:`flowrun.envs.rewards`.
"""

from __future__ import annotations

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.rewards import desired_velocities, wave_attenuation_rewards
from flowrun.envs.ring.accel import acceleration_box
from flowrun.envs.ring.wave_attenuation import partial_observation
from flowrun.fastring.plan import RingPlan
from flowrun.fastring.rings import FastRings
from flowrun.types import BoolArray, FloatArray


class RingTask:
    """Spaces, observation and reward of a plan's env class.

    Args:
        plan: the config's facts.
    """

    def __init__(self, plan: RingPlan) -> None:
        self.plan = plan
        additional = plan.cfg.env.additional_params
        self.action_space = acceleration_box(additional, int(plan.rl_rows.size))
        if plan.kind == "wave_po":
            self.observation_space = Box(low=-np.inf, high=np.inf, shape=(3,), dtype=np.float32)
        else:
            n = plan.num_cars
            self.observation_space = Box(low=0.0, high=1.0, shape=(2 * n,), dtype=np.float32)
        self.low = np.asarray(self.action_space.low, dtype=np.float64)
        self.high = np.asarray(self.action_space.high, dtype=np.float64)

    def clip(self, actions: np.ndarray) -> FloatArray:
        """Actions ``(B, num_rl)`` clipped to the action space (when ``clip_actions``), as
        ``(num_rl, B)`` float64 accelerations."""
        if self.low.size == 0:
            return np.zeros((0, np.shape(actions)[0]))
        a = np.asarray(actions, dtype=np.float64).reshape(-1, self.low.size)
        if self.plan.clip_actions:
            a = np.minimum(np.maximum(a, self.low), self.high)
        return np.ascontiguousarray(a.T)

    def observe(self, rings: FastRings) -> np.ndarray:
        """Every ring's observation, ``(B, obs_dim)`` float32."""
        s = rings.state
        assert s is not None
        p = self.plan
        if p.kind == "wave_po":
            if not p.rl_rows.size:
                return np.zeros((rings.num_rings, 3), dtype=np.float32)
            rl = int(p.rl_rows[0])
            if s.shared is not None:  # every ring has the same order: whole rows
                lead_row = int(s.shared[0][rl])
                u_lead, v_lead = s.u[lead_row], s.speed[lead_row]
            else:
                lead, cols = s.leader[rl], np.arange(rings.num_rings)
                u_lead, v_lead = s.u[lead, cols], s.speed[lead, cols]
            x_av = np.mod(s.u[rl], s.length)
            gap = np.mod(np.mod(u_lead, s.length) - x_av, s.length)
            obs = partial_observation(s.speed[rl], v_lead, gap, p.max_length)
            return obs.T.astype(np.float32)
        full = np.concatenate([s.speed / p.speed_limit, s.position / s.length])
        np.maximum(full, 0.0, out=full)
        np.minimum(full, 1.0, out=full)
        return np.ascontiguousarray(full.T, dtype=np.float32)

    def rewards(self, rings: FastRings, actions: FloatArray, crashed: BoolArray) -> FloatArray:
        """Every ring's reward for the step just taken (``actions`` as applied, ``(num_rl, B)``)."""
        s = rings.state
        assert s is not None
        p = self.plan
        if p.evaluate:
            return np.asarray(s.speed.mean(axis=0), dtype=np.float64)
        if p.kind == "accel":
            assert p.target_velocity is not None
            return desired_velocities(s.speed, p.target_velocity, crashed)
        return wave_attenuation_rewards(s.speed, actions, crashed)
