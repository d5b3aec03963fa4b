"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.scenarios.grid`` (now ``flowrun.networks``).
"""

from flowrun.networks.traffic_light_grid import ADDITIONAL_NET_PARAMS, SimpleGridScenario

__all__ = ["ADDITIONAL_NET_PARAMS", "SimpleGridScenario"]
