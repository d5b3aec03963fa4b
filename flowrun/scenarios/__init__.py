"""Flow compatibility: re-exports.

Flow's old names for networks (``flow.scenarios``): ``LoopScenario`` is the ring,
``Figure8Scenario``/``FigureEightScenario`` the figure eight, ``MergeScenario`` the merge and
``HighwayScenario`` the highway, ``BottleneckScenario`` the bottleneck,
``HighwayRampsScenario`` the highway with ramps and ``MiniCityScenario`` the mini city.
"""

from flowrun.networks.base import Network
from flowrun.networks.bottleneck import BottleneckScenario
from flowrun.networks.figure_eight import Figure8Scenario, FigureEightScenario
from flowrun.networks.highway import HighwayScenario
from flowrun.networks.highway_ramps import HighwayRampsScenario
from flowrun.networks.merge import MergeScenario
from flowrun.networks.minicity import MiniCityScenario
from flowrun.networks.ring import LoopScenario

#: Flow < 0.5 name of the network base class
Scenario = Network

__all__ = [
    "BottleneckScenario",
    "Figure8Scenario",
    "FigureEightScenario",
    "HighwayRampsScenario",
    "HighwayScenario",
    "LoopScenario",
    "MergeScenario",
    "MiniCityScenario",
    "Scenario",
]
