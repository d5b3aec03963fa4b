"""Flow compatibility: re-exports. Flow's ``flow.utils.rllib`` path.

``FlowParamsEncoder`` and ``get_flow_params`` live in :mod:`flowrun.envs.flow_json`,
``get_rllib_config`` and ``get_rllib_pkl`` in :mod:`flowrun.training.ray_results`.
"""

from flowrun.envs.flow_json import FlowParamsEncoder, get_flow_params
from flowrun.training.ray_results import get_rllib_config, get_rllib_pkl

__all__ = ["FlowParamsEncoder", "get_flow_params", "get_rllib_config", "get_rllib_pkl"]
