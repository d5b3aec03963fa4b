"""Flow compatibility: re-exports.

Flow's ``flow.envs.multiagent.i210`` import path
(flowrun's classes; importing it imports PettingZoo).
"""

from flowrun.multiagent.i210 import ADDITIONAL_ENV_PARAMS, I210MultiEnv

__all__ = ["ADDITIONAL_ENV_PARAMS", "I210MultiEnv"]
