"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.envs.loop.wave_attenuation``.
"""

from flowrun.envs.ring.wave_attenuation import (
    ADDITIONAL_ENV_PARAMS,
    WaveAttenuationEnv,
    WaveAttenuationPOEnv,
)

__all__ = ["ADDITIONAL_ENV_PARAMS", "WaveAttenuationEnv", "WaveAttenuationPOEnv"]
