"""``sim.backend: numpy``: many single-lane rings stepped at once with numpy, as SUMO steps them.

:func:`~flowrun.fastring.plan.ring_plan` checks a config (one :class:`~flowrun.errors.ConfigError`
for anything the backend cannot do); :class:`~flowrun.fastring.vec_env.RingVecEnv` is the
stable-baselines3 ``VecEnv`` and :class:`~flowrun.fastring.vec_env.RingVectorEnv` the Gymnasium
vector env over :class:`~flowrun.fastring.rings.FastRings`.
"""

from flowrun.fastring.plan import RingPlan, check_numpy_backend, ring_plan
from flowrun.fastring.rings import FastRings

__all__ = ["FastRings", "RingPlan", "check_numpy_backend", "ring_plan"]
