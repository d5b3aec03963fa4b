"""Flow compatibility: re-exports. Flow's older module path ``flow.envs.bottleneck_env``
(``DesiredVelocityEnv`` and co.); the envs live in :mod:`flowrun.envs.bottleneck`."""

from flowrun.envs.bottleneck import (
    ADDITIONAL_ENV_PARAMS,
    ADDITIONAL_RL_ENV_PARAMS,
    ADDITIONAL_VSL_ENV_PARAMS,
    BottleNeckAccelEnv,
    BottleneckAccelEnv,
    BottleneckDesiredVelocityEnv,
    BottleneckEnv,
    DesiredVelocityEnv,
)

__all__ = [
    "ADDITIONAL_ENV_PARAMS",
    "ADDITIONAL_RL_ENV_PARAMS",
    "ADDITIONAL_VSL_ENV_PARAMS",
    "BottleNeckAccelEnv",
    "BottleneckAccelEnv",
    "BottleneckDesiredVelocityEnv",
    "BottleneckEnv",
    "DesiredVelocityEnv",
]
