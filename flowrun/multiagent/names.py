"""Names of the multi-agent environments and where they live (no PettingZoo import here).

The env registry lists these names for ``env.class`` and imports a class only when a config
names it, so flowrun's core installs and imports without PettingZoo.
"""

from __future__ import annotations

#: ``env.class`` name -> ``module:Class`` of each multi-agent environment.
MULTIAGENT_ENVS: dict[str, str] = {
    "MultiAgentWaveAttenuationPOEnv": "flowrun.multiagent.ring:MultiAgentWaveAttenuationPOEnv",
    "MultiAgentAccelPOEnv": "flowrun.multiagent.ring:MultiAgentAccelPOEnv",
    "MultiAgentMergePOEnv": "flowrun.multiagent.merge:MultiAgentMergePOEnv",
    "MultiAgentHighwayPOEnv": "flowrun.multiagent.highway:MultiAgentHighwayPOEnv",
    "MultiTrafficLightGridPOEnv": "flowrun.multiagent.grid:MultiTrafficLightGridPOEnv",
}

#: The command that installs what the multi-agent environments need.
INSTALL_HINT = "pip install 'flowrun[multiagent]'  (or: pip install pettingzoo==1.27.0)"
