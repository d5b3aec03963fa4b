"""Flow's ``flow.core.params``: the parameter objects of an experiment.

Re-exported from :mod:`flowrun.config.params`, where the YAML config is built from the same
classes.
"""

from flowrun.config.params import (
    EnvParams,
    InFlows,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    TrafficLightParams,
    VehicleParams,
)

#: Flow >= 0.4 name of the simulator parameters (SUMO is the only simulator here).
SimParams = SumoParams

__all__ = [
    "EnvParams",
    "InFlows",
    "InitialConfig",
    "NetParams",
    "SimParams",
    "SumoCarFollowingParams",
    "SumoLaneChangeParams",
    "SumoParams",
    "TrafficLightParams",
    "VehicleParams",
]
