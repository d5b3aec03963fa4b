"""Flow's older module path ``flow.envs.bottleneck_env`` (``DesiredVelocityEnv`` and co.)."""

from flowrun.envs.bottleneck import ADDITIONAL_ENV_PARAMS, BottleneckEnv
from flowrun.envs.bottleneck_accel import ADDITIONAL_RL_ENV_PARAMS, BottleneckAccelEnv
from flowrun.envs.bottleneck_velocity import (
    ADDITIONAL_VSL_ENV_PARAMS,
    BottleneckDesiredVelocityEnv,
    DesiredVelocityEnv,
)

__all__ = [
    "ADDITIONAL_ENV_PARAMS",
    "ADDITIONAL_RL_ENV_PARAMS",
    "ADDITIONAL_VSL_ENV_PARAMS",
    "BottleneckAccelEnv",
    "BottleneckDesiredVelocityEnv",
    "BottleneckEnv",
    "DesiredVelocityEnv",
]
