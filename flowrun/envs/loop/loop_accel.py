"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.envs.loop.loop_accel``.
"""

from flowrun.envs.ring.accel import ADDITIONAL_ENV_PARAMS, AccelEnv

__all__ = ["ADDITIONAL_ENV_PARAMS", "AccelEnv"]
