"""Flow compatibility: re-exports. Flow's ``flow.utils.rllib`` path.

``FlowParamsEncoder`` and ``get_flow_params`` live in :mod:`flowrun.envs.flow_json`.
"""

from flowrun.envs.flow_json import FlowParamsEncoder, get_flow_params

__all__ = ["FlowParamsEncoder", "get_flow_params"]
