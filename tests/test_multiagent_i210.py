"""Flow's ``I210MultiEnv`` (every AV an agent, shared policy) on a three-lane highway with AV
inflows (it is not specific to the I-210's road; real SUMO)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from flowrun.controllers import IDMController, RLController
from flowrun.core.params import EnvParams, InFlows, NetParams, SumoParams, VehicleParams
from flowrun.envs.multiagent.i210 import I210MultiEnv
from flowrun.networks import HighwayNetwork
from flowrun.networks.highway import ADDITIONAL_NET_PARAMS
from flowrun.utils.registry import make_create_env


def flow_params(lead_obs: bool = True, horizon: int = 80) -> dict[str, Any]:
    vehicles = VehicleParams()
    vehicles.add("human", acceleration_controller=(IDMController, {}), num_vehicles=0)
    vehicles.add("rl", acceleration_controller=(RLController, {}), num_vehicles=0)
    inflows = InFlows()
    inflows.add(veh_type="human", edge="highway_0", vehs_per_hour=2400, depart_lane="free",
                depart_speed=20, name="human")
    inflows.add(veh_type="rl", edge="highway_0", vehs_per_hour=600, depart_lane="free",
                depart_speed=20, name="rl")  # fmt: skip
    net = dict(ADDITIONAL_NET_PARAMS, lanes=3, length=600)
    return dict(
        exp_tag="i210_like", env_name=I210MultiEnv, network=HighwayNetwork, simulator="traci",
        sim=SumoParams(sim_step=0.5, seed=1),
        env=EnvParams(horizon=horizon, warmup_steps=20, additional_params={
            "max_accel": 1, "max_decel": 1, "lead_obs": lead_obs}),
        net=NetParams(additional_params=net, inflows=inflows), veh=vehicles,
    )  # fmt: skip


@pytest.mark.sumo
def test_each_av_sees_its_leader_and_is_rewarded_by_the_mean_speed() -> None:
    env = make_create_env(flow_params())[0]()
    try:
        obs, _ = env.reset(seed=0)
        assert obs and all(a.startswith("rl_") for a in obs)
        assert env.observation_space.shape == (3,) and env.action_space("x").shape == (1,)
        vk = env.k.vehicle
        for agent, value in obs.items():
            lead = vk.get_leader(agent)
            lead_speed = vk.get_speed(lead) if lead else 0.0
            expected = [vk.get_speed(agent) / 50, vk.get_headway(agent) / 1000, lead_speed / 50]
            np.testing.assert_allclose(value, expected, rtol=1e-6)
        _, rewards, _, _, _ = env.step({a: np.array([0.0]) for a in env.agents})
        mean = float(np.mean(vk.get_speed(vk.get_ids())))
        for agent, reward in rewards.items():
            if agent not in env.agents:
                continue
            v, h = vk.get_speed(agent), vk.get_headway(agent)
            penalty = min((max(h / v, 0) - 1) / 1, 0) if vk.get_leader(agent) and v > 0 else 0
            assert reward == pytest.approx(max(mean + 0.1 * penalty, 0))
    finally:
        env.close()


@pytest.mark.sumo
def test_the_lane_observation_and_the_parallel_api() -> None:
    env = make_create_env(flow_params(lead_obs=False))[0]()
    try:
        obs, _ = env.reset(seed=0)
        assert env.observation_space.shape == (38,)
        value = next(iter(obs.values()))
        assert value.shape == (38,) and (value[3:6] == -1).all()  # 3 lanes, padded to 6
    finally:
        env.close()
    from pettingzoo.test import parallel_api_test

    env = make_create_env(flow_params(horizon=30))[0]()
    try:
        parallel_api_test(env, num_cycles=30)
    finally:
        env.close()
