"""Flow's "lord of the rings": ``MultiWaveAttenuationPOEnv`` on a ``MultiRingNetwork``, one AV
agent per ring rewarded for its own ring's traffic (Flow's lord_of_the_rings example with
flowrun imports, short horizon; real SUMO)."""

from __future__ import annotations

import numpy as np
import pytest

from flowrun.controllers import ContinuousRouter, IDMController, RLController
from flowrun.core.params import EnvParams, InitialConfig, NetParams, SumoParams, VehicleParams
from flowrun.envs.multiagent import MultiWaveAttenuationPOEnv
from flowrun.multiagent.rings import ring_reward
from flowrun.networks import MultiRingNetwork
from flowrun.utils.registry import make_create_env

NUM_RINGS = 2


def flow_params(horizon: int = 60) -> dict[str, object]:
    vehicles = VehicleParams()
    for i in range(NUM_RINGS):
        vehicles.add(veh_id=f"human_{i}", acceleration_controller=(IDMController, {"noise": 0.2}),
                     routing_controller=(ContinuousRouter, {}), num_vehicles=21)
        vehicles.add(veh_id=f"rl_{i}", acceleration_controller=(RLController, {}),
                     routing_controller=(ContinuousRouter, {}), num_vehicles=1)  # fmt: skip
    return dict(
        exp_tag=f"lord_of_numrings{NUM_RINGS}", env_name=MultiWaveAttenuationPOEnv,
        network=MultiRingNetwork, simulator="traci",
        sim=SumoParams(sim_step=0.1, render=False),
        env=EnvParams(horizon=horizon, warmup_steps=20, additional_params={
            "max_accel": 1, "max_decel": 1, "ring_length": [230, 230], "target_velocity": 4}),
        net=NetParams(additional_params={"length": 230, "lanes": 1, "speed_limit": 30,
                                         "resolution": 40, "num_rings": NUM_RINGS}),
        veh=vehicles, initial=InitialConfig(bunching=20.0),
    )  # fmt: skip


def test_ring_reward_on_hand_numbers() -> None:
    assert ring_reward(np.array([4.0, 4.0]), 4.0) == pytest.approx(1.0)
    # |t| = 4*sqrt(2), |v - t| = 4: (5.657 - 4) / 5.657
    assert ring_reward(np.array([0.0, 4.0]), 4.0) == pytest.approx(1 - 1 / np.sqrt(2))
    assert ring_reward(np.array([]), 4.0) == 0.0


@pytest.mark.sumo
def test_one_agent_per_ring_each_rewarded_for_its_ring() -> None:
    create, _ = make_create_env(flow_params())
    env = create()
    try:
        obs, _ = env.reset(seed=0)
        assert sorted(obs) == ["rl_0_0", "rl_1_0"] and obs["rl_0_0"].shape == (3,)
        assert env.action_space("rl_1_0").shape == (1,)
        vk = env.k.vehicle
        assert {vk.get_edge(a).rsplit("_", 1)[1] for a in obs} == {"0", "1"}
        _, rewards, _, _, _ = env.step({"rl_0_0": np.array([1.0]), "rl_1_0": np.array([-1.0])})
        for agent, ring in (("rl_0_0", "0"), ("rl_1_0", "1")):
            speeds = [vk.get_speed(v) for v in vk.get_ids()
                      if vk.get_route(v)[0].rsplit("_", 1)[1] == ring]  # fmt: skip
            assert len(speeds) == 22
            assert rewards[agent] == pytest.approx(ring_reward(np.array(speeds), 4.0))
    finally:
        env.close()
    from pettingzoo.test import parallel_api_test

    env = make_create_env(flow_params(horizon=20))[0]()
    try:
        parallel_api_test(env, num_cycles=20)
    finally:
        env.close()
