"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.envs.loop.lane_changing``.
"""

from flowrun.envs.ring.lane_change import ADDITIONAL_ENV_PARAMS, LaneChangeAccelEnv

__all__ = ["ADDITIONAL_ENV_PARAMS", "LaneChangeAccelEnv"]
