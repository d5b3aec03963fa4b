"""Flow compatibility: re-exports.

Flow's ``flow.envs.multiagent.ring.accel`` import path
(flowrun's classes; importing it imports PettingZoo).
"""

from flowrun.multiagent.adversarial import AdversarialAccelEnv
from flowrun.multiagent.ring import MultiAgentAccelPOEnv

__all__ = ["AdversarialAccelEnv", "MultiAgentAccelPOEnv"]
