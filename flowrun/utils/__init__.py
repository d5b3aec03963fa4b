"""Flow compatibility: re-exports.

Flow's ``flow.utils``: ``registry.make_create_env`` and ``env_constructor``,
``rllib.FlowParamsEncoder`` and ``get_flow_params``, ``exceptions.FatalFlowError``.
"""
