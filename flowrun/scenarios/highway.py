"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.scenarios.highway`` (now ``flowrun.networks``).
"""

from flowrun.networks.highway import ADDITIONAL_NET_PARAMS, HighwayScenario

__all__ = ["ADDITIONAL_NET_PARAMS", "HighwayScenario"]
