"""Flow compatibility: re-exports.

Flow's ``flow.envs.multiagent.merge`` import path
(flowrun's classes; importing it imports PettingZoo).
"""

from flowrun.multiagent.merge import MultiAgentMergePOEnv

__all__ = ["MultiAgentMergePOEnv"]
