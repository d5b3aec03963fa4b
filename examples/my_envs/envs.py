"""The environment of Flow's tutorial "Creating custom environments", on flowrun.

A central agent sets the accelerations of the RL cars; it observes the position and speed of
every car and is rewarded with the mean speed of all cars.
"""

from typing import Any

import numpy as np
from gymnasium.spaces.box import Box

from flowrun.envs import Env

ADDITIONAL_ENV_PARAMS = {
    # maximum acceleration of the RL cars, m/s^2
    "max_accel": 1,
    # maximum deceleration of the RL cars, m/s^2
    "max_decel": 1,
}


class MyEnv(Env):
    """Mixed-autonomy ring with global observations (the tutorial's ``myEnv``).

    Observation: positions (m along the ring) then speeds (m/s) of all cars, ``2 * N`` values.
    Action: one acceleration per RL car in ``[-max_decel, max_accel]`` m/s^2.
    Reward: mean speed of all cars, m/s.
    """

    ADDITIONAL_ENV_PARAMS = ADDITIONAL_ENV_PARAMS

    @property
    def action_space(self) -> Box:
        """One acceleration per RL car."""
        num_actions = self.initial_vehicles.num_rl_vehicles
        accel_ub = self.env_params.additional_params["max_accel"]
        accel_lb = -abs(self.env_params.additional_params["max_decel"])
        return Box(low=accel_lb, high=accel_ub, shape=(num_actions,))

    @property
    def observation_space(self) -> Box:
        """Position and speed of every car."""
        return Box(low=0, high=float("inf"), shape=(2 * self.initial_vehicles.num_vehicles,))

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        # the names of all autonomous (RL) vehicles in the network
        rl_ids = self.k.vehicle.get_rl_ids()
        # the kernel turns accelerations into next-step speeds for the RL vehicles
        self.k.vehicle.apply_acceleration(rl_ids, rl_actions)

    def get_state(self, **kwargs: Any) -> np.ndarray:
        """Positions then speeds of all cars."""
        ids = self.k.vehicle.get_ids()
        pos = [self.k.vehicle.get_x_by_id(veh_id) for veh_id in ids]
        vel = [self.k.vehicle.get_speed(veh_id) for veh_id in ids]
        return np.concatenate((pos, vel))

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Mean speed of all cars, m/s."""
        ids = self.k.vehicle.get_ids()
        speeds = self.k.vehicle.get_speed(ids)
        return float(np.mean(speeds))


#: The tutorial's spelling of the class name.
myEnv = MyEnv
