"""Environments: Flow's ``Env`` base on Gymnasium, the ring tasks and the merge."""

from flowrun.envs.base import Env
from flowrun.envs.bottleneck import (
    BottleNeckAccelEnv,
    BottleneckAccelEnv,
    BottleneckDesiredVelocityEnv,
    BottleneckEnv,
    DesiredVelocityEnv,
)
from flowrun.envs.merge import MergePOEnv
from flowrun.envs.registry import env_names, register_envs, resolve_env_class
from flowrun.envs.ring.accel import AccelEnv
from flowrun.envs.ring.lane_change import LaneChangeAccelEnv, LaneChangeAccelPOEnv
from flowrun.envs.ring.wave_attenuation import WaveAttenuationEnv, WaveAttenuationPOEnv
from flowrun.envs.test import TestEnv
from flowrun.envs.traffic_light_grid import (
    GreenWaveTestEnv,
    PO_TrafficLightGridEnv,
    TrafficLightGridBenchmarkEnv,
    TrafficLightGridEnv,
    TrafficLightGridPOEnv,
    TrafficLightGridTestEnv,
)

register_envs()

__all__ = [
    "AccelEnv",
    "BottleNeckAccelEnv",
    "BottleneckAccelEnv",
    "BottleneckDesiredVelocityEnv",
    "BottleneckEnv",
    "DesiredVelocityEnv",
    "Env",
    "GreenWaveTestEnv",
    "LaneChangeAccelEnv",
    "LaneChangeAccelPOEnv",
    "MergePOEnv",
    "PO_TrafficLightGridEnv",
    "TestEnv",
    "TrafficLightGridBenchmarkEnv",
    "TrafficLightGridEnv",
    "TrafficLightGridPOEnv",
    "TrafficLightGridTestEnv",
    "WaveAttenuationEnv",
    "WaveAttenuationPOEnv",
    "env_names",
    "register_envs",
    "resolve_env_class",
]
