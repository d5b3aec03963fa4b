"""Flow's ``NonLocalFollowerStopper``: a FollowerStopper whose desired speed is the network's
mean speed at each step (real SUMO ring)."""

from __future__ import annotations

import numpy as np
import pytest

from flowrun.controllers import ContinuousRouter, IDMController, NonLocalFollowerStopper
from flowrun.controllers.registry import resolve_controller
from flowrun.controllers.velocity import follower_stopper_speed
from flowrun.core.params import VehicleParams
from flowrun.utils.registry import env_constructor
from tests.test_flow_params import ring_params


def test_registered_and_driven_per_vehicle() -> None:
    assert resolve_controller("NonLocalFollowerStopper") is NonLocalFollowerStopper
    assert NonLocalFollowerStopper.per_vehicle  # it reads the whole network: Flow's get_accel


@pytest.mark.sumo
def test_the_command_follows_the_networks_mean_speed() -> None:
    vehicles = VehicleParams()
    vehicles.add(veh_id="fs", acceleration_controller=(NonLocalFollowerStopper, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=2)
    vehicles.add(veh_id="idm", acceleration_controller=(IDMController, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=12)  # fmt: skip
    env = env_constructor(ring_params(veh=vehicles))()
    try:
        env.reset(seed=0)
        for _ in range(60):
            env.step(None)
        vk = env.k.vehicle
        mean = float(np.mean(vk.get_speed(vk.get_ids())))
        for vid in ("fs_0", "fs_1"):
            v, h = vk.get_speed(vid), vk.get_headway(vid)
            v_lead = vk.get_speed(vk.get_leader(vid))
            v_cmd = follower_stopper_speed(np.array([v]), np.array([h]), np.array([v_lead]),
                                           v_des=mean)  # fmt: skip
            got = NonLocalFollowerStopper(veh_id=vid).get_accel(env)
            assert got == pytest.approx((v_cmd[0] - v) / 0.1)
        assert 0.5 < mean < 10  # the FollowerStopper cars move with the traffic
        # Flow's FollowerStopper helper, on the per-vehicle controller the kernel holds
        for vid in ("fs_0", "fs_1"):
            ctrl = vk.get_acc_controller(vid)
            edge = vk.get_edge(vid)
            expected = env.k.network.edge_length(edge) - vk.get_position(vid)
            assert ctrl.find_intersection_dist(env) == pytest.approx(expected)
            assert 0 <= expected <= env.k.network.edge_length(edge)
    finally:
        env.close()
