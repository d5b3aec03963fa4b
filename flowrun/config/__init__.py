"""Typed, validated experiment configuration (the YAML file and Flow's parameter objects).

Reading a file into a checked :class:`ExperimentConfig` (which builds its network to check
it) is one layer up, in :mod:`flowrun.loading`.

Also Flow's ``flow.config`` settings that still mean something: :data:`PROJECT_PATH` (the
folder holding the package) and :data:`LOG_DIR` (``PROJECT_PATH/data``).
"""

from pathlib import Path as _Path

from flowrun.config.model import ExperimentConfig, NetworkConfig, TrainConfig
from flowrun.config.params import (
    ControllerSpec,
    EnvParams,
    InFlow,
    InFlows,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    TrafficLightParams,
    VehicleParams,
    VehicleType,
)

__all__ = [
    "LOG_DIR",
    "PROJECT_PATH",
    "ControllerSpec",
    "EnvParams",
    "ExperimentConfig",
    "InFlow",
    "InFlows",
    "InitialConfig",
    "NetParams",
    "NetworkConfig",
    "SumoCarFollowingParams",
    "SumoLaneChangeParams",
    "SumoParams",
    "TrafficLightParams",
    "TrainConfig",
    "VehicleParams",
    "VehicleType",
]

from flowrun.config.dump import config_to_dict, dump_config

__all__ += ["config_to_dict", "dump_config"]

#: the folder that holds the ``flowrun`` package (Flow's ``flow.config.PROJECT_PATH``)
PROJECT_PATH = str(_Path(__file__).resolve().parents[2])
#: Flow's default data folder, ``PROJECT_PATH/data``
LOG_DIR = PROJECT_PATH + "/data"
