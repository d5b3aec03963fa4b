"""Networks described as data and converted to SUMO networks."""

from flowrun.networks.base import Network, NetworkSpec, StartPositions
from flowrun.networks.ring import ADDITIONAL_NET_PARAMS, RingNetwork

__all__ = ["ADDITIONAL_NET_PARAMS", "Network", "NetworkSpec", "RingNetwork", "StartPositions"]
