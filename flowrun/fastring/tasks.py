"""The ring envs' tasks for many rings at once: the env class's own task
(:mod:`flowrun.envs.ring.tasks`, named by its ``RING_TASK``) over the numpy backend's state."""

from __future__ import annotations

import numpy as np

from flowrun.envs.factory import env_class
from flowrun.envs.ring.accel import RingAccelBase
from flowrun.envs.ring.tasks import RingBatch
from flowrun.fastring.plan import RingPlan
from flowrun.fastring.rings import FastRings
from flowrun.types import BoolArray, FloatArray


class RingTask:
    """Spaces, observation and reward of a plan's env class, over :class:`FastRings`.

    Args:
        plan: the config's facts.
    """

    def __init__(self, plan: RingPlan) -> None:
        self.plan = plan
        cls = env_class(plan.cfg)
        assert issubclass(cls, RingAccelBase), "ring_plan() admits the ring envs only"
        self.task = cls.RING_TASK(
            plan.cfg.env.additional_params, plan.num_cars, plan.rl_rows, plan.speed_limit,
            plan.max_length, plan.evaluate,
        )  # fmt: skip
        self.action_space = self.task.action_space
        self.observation_space = self.task.observation_space
        self._batch: RingBatch | None = None

    def clip(self, actions: np.ndarray) -> FloatArray:
        """Actions ``(B, num_rl)`` clipped to the action space (when ``clip_actions``), as
        ``(num_rl, B)`` float64 accelerations."""
        return self.task.accelerations(actions, self.plan.clip_actions)

    def rings(self, rings: FastRings) -> RingBatch:
        """The rings' state now as the task sees it (made once per step)."""
        s = rings.state
        assert s is not None
        batch = self._batch
        if batch is None or batch.speed is not s.speed or batch.distance is not s.u:
            leader = s.shared[0] if s.shared is not None else s.leader
            batch = self._batch = RingBatch(s.speed, s.u, s.length, leader)
        return batch

    def observe(self, rings: FastRings) -> np.ndarray:
        """Every ring's observation, ``(B, obs_dim)`` float32."""
        return np.ascontiguousarray(self.task.observe(self.rings(rings)).T, dtype=np.float32)

    def rewards(self, rings: FastRings, actions: FloatArray, crashed: BoolArray) -> FloatArray:
        """Every ring's reward for the step just taken (``actions`` as applied, ``(num_rl, B)``)."""
        return self.task.rewards(self.rings(rings), actions, crashed)
