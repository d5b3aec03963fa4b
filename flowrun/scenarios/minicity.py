"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.scenarios.minicity`` (now ``flowrun.networks``).
"""

from flowrun.networks.minicity import ADDITIONAL_NET_PARAMS, MiniCityScenario

__all__ = ["ADDITIONAL_NET_PARAMS", "MiniCityScenario"]
