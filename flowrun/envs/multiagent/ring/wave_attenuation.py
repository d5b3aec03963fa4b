"""Flow compatibility: re-exports.

Flow's ``flow.envs.multiagent.ring.wave_attenuation`` import path
(flowrun's classes; importing it imports PettingZoo).
"""

from flowrun.multiagent.ring import MultiAgentWaveAttenuationPOEnv

__all__ = ["MultiAgentWaveAttenuationPOEnv"]
