"""Networks described as data and converted to SUMO networks."""

from flowrun.networks.base import Network, NetworkSpec, StartPositions
from flowrun.networks.bottleneck import BottleneckNetwork
from flowrun.networks.figure_eight import FigureEightNetwork
from flowrun.networks.highway import HighwayNetwork
from flowrun.networks.highway_ramps import HighwayRampsNetwork
from flowrun.networks.i210_subnetwork import I210SubNetwork
from flowrun.networks.merge import MergeNetwork
from flowrun.networks.minicity import MiniCityNetwork
from flowrun.networks.multi_ring import MultiRingNetwork
from flowrun.networks.ring import ADDITIONAL_NET_PARAMS, RingNetwork
from flowrun.networks.template import TemplateNetwork
from flowrun.networks.traffic_light_grid import TrafficLightGridNetwork

__all__ = [
    "ADDITIONAL_NET_PARAMS",
    "BottleneckNetwork",
    "FigureEightNetwork",
    "HighwayNetwork",
    "HighwayRampsNetwork",
    "I210SubNetwork",
    "MergeNetwork",
    "MiniCityNetwork",
    "MultiRingNetwork",
    "Network",
    "NetworkSpec",
    "RingNetwork",
    "StartPositions",
    "TemplateNetwork",
    "TrafficLightGridNetwork",
]
