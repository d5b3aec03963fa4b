"""Flow compatibility: re-exports. Flow's ``flow.core.rewards`` path.

The functions (Flow's reward functions that take the env) live in
:mod:`flowrun.envs.flow_rewards`; the pure formulas behind them in :mod:`flowrun.envs.rewards`.
"""

from flowrun.envs.flow_rewards import (
    average_velocity,
    avg_delay_specified_vehicles,
    boolean_action_penalty,
    desired_velocity,
    energy_consumption,
    miles_per_gallon,
    miles_per_megajoule,
    min_delay,
    min_delay_unscaled,
    penalize_headway_variance,
    penalize_near_standstill,
    penalize_standstill,
    punish_queues_in_lane,
    punish_rl_lane_changes,
    punish_small_rl_headways,
    reward_rl_opening_headways,
    rl_forward_progress,
    total_velocity,
    veh_energy_consumption,
    vehicle_energy_consumption,
)

__all__ = [
    "average_velocity",
    "avg_delay_specified_vehicles",
    "boolean_action_penalty",
    "desired_velocity",
    "energy_consumption",
    "miles_per_gallon",
    "miles_per_megajoule",
    "min_delay",
    "min_delay_unscaled",
    "penalize_headway_variance",
    "penalize_near_standstill",
    "penalize_standstill",
    "punish_queues_in_lane",
    "punish_rl_lane_changes",
    "punish_small_rl_headways",
    "reward_rl_opening_headways",
    "rl_forward_progress",
    "total_velocity",
    "veh_energy_consumption",
    "vehicle_energy_consumption",
]
