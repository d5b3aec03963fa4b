"""Flow compatibility: re-exports.

Flow's ``flow.core.params``: the parameter objects of an experiment.

Re-exported from :mod:`flowrun.config.params`, where the YAML config is built from the same
classes.
"""

from flowrun.config.modes import LANE_CHANGE_MODES, SPEED_MODES
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

#: Flow's name of the lane-change mode table
LC_MODES = LANE_CHANGE_MODES

#: Flow >= 0.4 name of the simulator parameters (SUMO is the only simulator here).
SimParams = SumoParams

__all__ = [
    "LC_MODES",
    "SPEED_MODES",
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
