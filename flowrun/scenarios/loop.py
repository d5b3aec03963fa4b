"""Flow compatibility: re-exports.

``LoopScenario`` (Flow < 0.5 name of the ring network) and its ``ADDITIONAL_NET_PARAMS``.
"""

from flowrun.networks.ring import ADDITIONAL_NET_PARAMS, RingNetwork

LoopScenario = RingNetwork

__all__ = ["ADDITIONAL_NET_PARAMS", "LoopScenario"]
