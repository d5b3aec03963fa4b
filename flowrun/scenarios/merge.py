"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.scenarios.merge`` (now ``flowrun.networks``).
"""

from flowrun.networks.merge import ADDITIONAL_NET_PARAMS, MergeScenario

__all__ = ["ADDITIONAL_NET_PARAMS", "MergeScenario"]
