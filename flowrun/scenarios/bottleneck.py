"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.scenarios.bottleneck`` (now ``flowrun.networks``).
"""

from flowrun.networks.bottleneck import ADDITIONAL_NET_PARAMS, BottleneckScenario

__all__ = ["ADDITIONAL_NET_PARAMS", "BottleneckScenario"]
