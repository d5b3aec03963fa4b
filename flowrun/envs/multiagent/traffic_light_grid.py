"""Flow compatibility: re-exports.

Flow's ``flow.envs.multiagent.traffic_light_grid`` import path
(flowrun's classes; importing it imports PettingZoo).
"""

from flowrun.multiagent.grid import MultiTrafficLightGridPOEnv

__all__ = ["MultiTrafficLightGridPOEnv"]
