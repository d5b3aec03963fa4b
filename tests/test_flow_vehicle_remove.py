"""``k.vehicle.remove(id)`` as Flow: the car is gone from every getter at once, although the
kernel's arrays drop its row only at the next simulation step, and it gets no command in that
step (real SUMO: a short ring, and the figure eight for the step after a removal)."""

from __future__ import annotations

import pytest

from flowrun.config.params import EnvParams, NetParams, SumoParams, VehicleParams
from flowrun.controllers import ContinuousRouter, IDMController, RLController
from flowrun.envs import TestEnv
from flowrun.errors import SimulationError
from flowrun.networks import RingNetwork
from tests.test_open_kernel import on_network


def ring_env() -> TestEnv:
    vehicles = VehicleParams()
    vehicles.add("test", acceleration_controller=(IDMController, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=4)  # fmt: skip
    vehicles.add("test_rl", acceleration_controller=(RLController, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=2)  # fmt: skip
    net = NetParams(additional_params={"length": 230, "lanes": 1, "speed_limit": 30,
                                       "resolution": 40})  # fmt: skip
    env = TestEnv(EnvParams(), SumoParams(sim_step=0.1), RingNetwork("rm", vehicles, net))
    env.reset(seed=0)
    return env


def test_a_removed_car_leaves_every_getter_in_the_same_step() -> None:
    env = ring_env()
    try:
        vk = env.k.vehicle
        speed_before = vk.get_speed("test_1")
        vk.remove("test_0")
        vk.remove("test_rl_0")
        assert "test_0" not in vk.get_ids() and "test_rl_0" not in vk.get_ids()
        assert vk.get_human_ids() == ["test_1", "test_2", "test_3"]
        assert vk.get_rl_ids() == ["test_rl_1"]
        assert "test_0" not in vk.get_controlled_ids()
        assert vk.num_vehicles == 4 == len(vk.get_ids())
        assert vk.num_rl_vehicles == 1
        assert vk.get_speed("test_0", error=None) is None
        assert vk.get_speed(["test_0", "test_1"], error=-1) == [-1, speed_before]
        # the ring's fixed population cannot go on without them: one clear error, not SUMO's
        with pytest.raises(SimulationError, match=r"remove\('test_0', 'test_rl_0'\)"):
            env.step(None)
    finally:
        env.close()


def test_the_step_after_a_removal_commands_only_the_cars_still_there() -> None:
    env = on_network("figure_eight")
    env.reset(seed=0)
    try:
        vk = env.k.vehicle
        env.step(None)
        vk.remove("human_3")
        assert vk.num_vehicles == 13
        env.step(None)  # IDM computed an acceleration for every row; human_3 gets none
        assert "human_3" not in vk.get_ids() and vk.num_vehicles == 13
        assert "human_3" not in vk.api.vehicle.getIDList()
        env.step(None)
        assert len(vk.get_ids()) == 13
    finally:
        env.close()
