"""Flow's ``flow.core.rewards``, as pure functions of arrays (see :mod:`flowrun.envs.rewards`).

Unlike Flow's, these take the speeds (and actions) instead of the whole env:
``desired_velocity(env.k.vehicle.speed, target_velocity)``.
"""

from flowrun.envs.rewards import desired_velocity, wave_attenuation_terms

__all__ = ["desired_velocity", "wave_attenuation_terms"]
