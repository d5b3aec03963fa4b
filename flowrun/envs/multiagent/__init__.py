"""Flow compatibility: re-exports.

Flow's module path ``flow.envs.multiagent``: the classes of :mod:`flowrun.multiagent`.

``from flowrun.envs.multiagent import MultiAgentWaveAttenuationPOEnv`` works as Flow's import
did (PettingZoo is imported with the class, not with :mod:`flowrun.envs`).
"""

from __future__ import annotations

from typing import Any

import flowrun.multiagent as _multiagent

__all__ = [
    "AdversarialAccelEnv",
    "I210MultiEnv",
    "MultiAgentAccelPOEnv",
    "MultiAgentHighwayPOEnv",
    "MultiAgentMergePOEnv",
    "MultiAgentWaveAttenuationPOEnv",
    "MultiEnv",
    "MultiTrafficLightGridPOEnv",
    "MultiWaveAttenuationPOEnv",
]


def __getattr__(name: str) -> Any:
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(_multiagent, name)
