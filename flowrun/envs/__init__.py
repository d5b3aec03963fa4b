"""Environments: Flow's ``Env`` base on Gymnasium, the ring tasks and the merge."""

from flowrun.envs.base import Env
from flowrun.envs.bottleneck import (
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
    TrafficLightGridBenchmarkEnv,
    TrafficLightGridEnv,
    TrafficLightGridPOEnv,
)

register_envs()

__all__ = [
    "AccelEnv",
    "BottleneckAccelEnv",
    "BottleneckDesiredVelocityEnv",
    "BottleneckEnv",
    "DesiredVelocityEnv",
    "Env",
    "LaneChangeAccelEnv",
    "LaneChangeAccelPOEnv",
    "MergePOEnv",
    "TestEnv",
    "TrafficLightGridBenchmarkEnv",
    "TrafficLightGridEnv",
    "TrafficLightGridPOEnv",
    "WaveAttenuationEnv",
    "WaveAttenuationPOEnv",
    "env_names",
    "register_envs",
    "resolve_env_class",
]
