"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.scenarios.highway_ramps`` (now ``flowrun.networks``).
"""

from flowrun.networks.highway_ramps import ADDITIONAL_NET_PARAMS, HighwayRampsScenario

__all__ = ["ADDITIONAL_NET_PARAMS", "HighwayRampsScenario"]
