"""Environments: Flow's ``Env`` base on Gymnasium, the ring tasks and the merge."""

from typing import TYPE_CHECKING, Any

from flowrun.envs.registry import env_names, register_envs, resolve_env_class

if TYPE_CHECKING:
    from flowrun.envs.base import Env
    from flowrun.envs.bottleneck import (
        BottleNeckAccelEnv,
        BottleneckAccelEnv,
        BottleneckDesiredVelocityEnv,
        BottleneckEnv,
        DesiredVelocityEnv,
    )
    from flowrun.envs.merge import MergePOEnv
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


def __getattr__(name: str) -> Any:
    """The environment classes, imported on first use (``flowrun list envs`` imports none)."""
    if name not in __all__:
        raise AttributeError(f"module 'flowrun.envs' has no attribute '{name}'")
    from flowrun.envs import base, bottleneck, merge, test, traffic_light_grid
    from flowrun.envs.ring import accel, lane_change, wave_attenuation

    modules = (base, bottleneck, merge, test, traffic_light_grid, accel, lane_change,
               wave_attenuation)  # fmt: skip
    value = next(getattr(m, name) for m in modules if hasattr(m, name))
    globals()[name] = value
    return value


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
