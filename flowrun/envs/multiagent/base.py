"""Flow compatibility: re-exports.

Flow's ``flow.envs.multiagent.base`` import path
(flowrun's classes; importing it imports PettingZoo).
"""

from flowrun.multiagent.base import MultiAgentEnv, MultiEnv

__all__ = ["MultiAgentEnv", "MultiEnv"]
