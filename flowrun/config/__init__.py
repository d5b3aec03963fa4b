"""Typed, validated experiment configuration (the YAML file and Flow's parameter objects)."""

from flowrun.config.model import ExperimentConfig, NetworkConfig, TrainConfig
from flowrun.config.params import (
    ControllerSpec,
    EnvParams,
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
