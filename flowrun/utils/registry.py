"""Flow compatibility: re-exports. Flow's ``flow.utils.registry`` path.

``make_create_env`` and ``env_constructor`` live in :mod:`flowrun.envs.flow_params`.
"""

from flowrun.envs.flow_params import (
    env_constructor,
    flow_network,
    make_create_env,
    make_flow_env,
)

__all__ = ["env_constructor", "flow_network", "make_create_env", "make_flow_env"]
