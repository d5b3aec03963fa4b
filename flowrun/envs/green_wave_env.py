"""Flow compatibility: re-exports. Flow < 0.5 module path ``flow.envs.green_wave_env``; the
envs live in :mod:`flowrun.envs.traffic_light_grid`."""

from flowrun.envs.traffic_light_grid import (
    GreenWaveTestEnv,
    PO_TrafficLightGridEnv,
    TrafficLightGridEnv,
    TrafficLightGridPOEnv,
)

__all__ = ["GreenWaveTestEnv", "PO_TrafficLightGridEnv", "TrafficLightGridEnv",
           "TrafficLightGridPOEnv"]  # fmt: skip
