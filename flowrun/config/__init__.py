"""Typed, validated experiment configuration (the YAML file and Flow's parameter objects)."""

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
from flowrun.config.loader import config_from_dict, load_config

__all__ += ["config_from_dict", "config_to_dict", "dump_config", "load_config"]
