"""Flow's ``NonLocalFollowerStopper``: a FollowerStopper whose desired speed is the mean speed
of every vehicle in the network, recomputed at every step (Flow's
``flow/controllers/velocity_controllers.py``).

It reads the whole network, so it is written Flow's way, per vehicle (``get_accel(env)``):
the environment makes one object per vehicle and applies Flow's noise and fail-safes to its
command (:mod:`flowrun.controllers.per_vehicle`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from flowrun.controllers.limits import DEFAULT_MAX_ACCEL, DEFAULT_MAX_DECEL, vehicle_limits
from flowrun.controllers.velocity import FollowerStopper, follower_stopper_speed
from flowrun.controllers.view import intersection_distance, read_inputs


class NonLocalFollowerStopper(FollowerStopper):
    """Stern et al.'s FollowerStopper with ``v_des`` = the network's mean speed, m/s.

    Returns ``None`` (SUMO drives the car this step) when the network is empty or the car is
    in a junction or on one of ``danger_edges``, as Flow's controller hands such cars back to
    SUMO. The command is not clipped to the vehicle's limits (Flow's is not either).
    """

    registered_name = "NonLocalFollowerStopper"

    def get_accel(self, env: Any) -> float | None:  # type: ignore[override]
        """The acceleration of this vehicle now, m/s^2 (Flow's per-vehicle signature)."""
        vk = env.k.vehicle
        ids = vk.get_ids()
        veh_id = str(self.veh_id)
        if not ids or veh_id not in ids:
            return None
        edge = vk.get_edge(veh_id)
        if not edge or edge.startswith(":") or edge in (self.danger_edges or ()):
            return None
        v_des = float(np.mean(vk.get_speed(ids)))
        max_accel, max_decel = (
            vehicle_limits(self.car_following_params) or (DEFAULT_MAX_ACCEL, DEFAULT_MAX_DECEL)
        )
        x = read_inputs(env, veh_id, max_accel, max_decel)
        v_cmd = follower_stopper_speed(
            x.speed, x.headway, x.leader_speed,
            v_des=v_des, dx_1_0=self.dx_1_0, dx_2_0=self.dx_2_0, dx_3_0=self.dx_3_0,
            d_1=self.d_1, d_2=self.d_2, d_3=self.d_3,
        )  # fmt: skip
        return float((v_cmd[0] - x.speed[0]) / x.dt)  # unclipped, as Flow's

    def find_intersection_dist(self, env: Any) -> float:
        """Distance (m) from this car to the end of its edge, as FollowerStopper's (Flow's
        ``find_intersection_dist``): -10 without an edge, 0 on a grid junction's edge."""
        return intersection_distance(env, str(self.veh_id))
