"""Flow compatibility: re-exports.

Flow's ``flow.envs.multiagent.ring.wave_attenuation`` import path
(flowrun's classes; importing it imports PettingZoo).
"""

from flowrun.multiagent.ring import MultiAgentWaveAttenuationPOEnv
from flowrun.multiagent.rings import MultiWaveAttenuationPOEnv

__all__ = ["MultiAgentWaveAttenuationPOEnv", "MultiWaveAttenuationPOEnv"]
