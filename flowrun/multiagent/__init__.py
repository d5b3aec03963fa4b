"""Multi-agent environments: Flow's ``flow.envs.multiagent`` as PettingZoo ``ParallelEnv``s.

Each autonomous vehicle is an agent (agent id = vehicle id). The classes need the
``multiagent`` extra (PettingZoo); they are imported on first use, so ``import
flowrun.multiagent`` itself does not import PettingZoo.
"""

from __future__ import annotations

import importlib
from typing import Any

from flowrun.envs.registry import INSTALL_HINT, MULTIAGENT_ENVS

__all__ = [
    "INSTALL_HINT",
    "MULTIAGENT_ENVS",
    "AdversarialAccelEnv",
    "I210MultiEnv",
    "MultiAgentAccelPOEnv",
    "MultiAgentEnv",
    "MultiAgentHighwayPOEnv",
    "MultiAgentMergePOEnv",
    "MultiAgentWaveAttenuationPOEnv",
    "MultiEnv",
    "MultiTrafficLightGridPOEnv",
    "MultiWaveAttenuationPOEnv",
]

_LAZY = {name: path for name, path in MULTIAGENT_ENVS.items()} | {
    "MultiAgentEnv": "flowrun.multiagent.base:MultiAgentEnv",
    "MultiEnv": "flowrun.multiagent.base:MultiEnv",
}


def __getattr__(name: str) -> Any:
    path = _LAZY.get(name)
    if path is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module_name, _, attr = path.partition(":")
    return getattr(importlib.import_module(module_name), attr)
