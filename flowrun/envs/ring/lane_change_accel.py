"""Flow's module path ``flow.envs.ring.lane_change_accel`` (the env lives in ``lane_change``)."""

from flowrun.envs.ring.lane_change import (
    ADDITIONAL_ENV_PARAMS,
    LaneChangeAccelEnv,
    LaneChangeAccelPOEnv,
)

__all__ = ["ADDITIONAL_ENV_PARAMS", "LaneChangeAccelEnv", "LaneChangeAccelPOEnv"]
