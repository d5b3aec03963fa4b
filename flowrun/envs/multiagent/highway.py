"""Flow compatibility: re-exports.

Flow's ``flow.envs.multiagent.highway`` import path
(flowrun's classes; importing it imports PettingZoo).
"""

from flowrun.multiagent.highway import MultiAgentHighwayPOEnv

__all__ = ["MultiAgentHighwayPOEnv"]
