"""Flow's ``AdversarialAccelEnv`` on the figure eight (Flow's adversarial_figure_eight example
with flowrun imports, short horizon): agents ``av`` and ``adversary``, the RL car driven by
``av + perturb_weight * adversary``, opposite rewards (real SUMO)."""

from __future__ import annotations

from copy import deepcopy
from typing import Any

import numpy as np
import pytest
from gymnasium.spaces import Box

from flowrun.controllers import ContinuousRouter, IDMController, RLController
from flowrun.core.params import (
    EnvParams,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoParams,
    VehicleParams,
)
from flowrun.envs.multiagent import AdversarialAccelEnv
from flowrun.networks import FigureEightNetwork
from flowrun.networks.figure_eight import ADDITIONAL_NET_PARAMS
from flowrun.utils.registry import make_create_env


def flow_params(horizon: int = 50) -> dict[str, Any]:
    vehicles = VehicleParams()
    vehicles.add(veh_id="human", acceleration_controller=(IDMController, {"noise": 0.2}),
                 routing_controller=(ContinuousRouter, {}),
                 car_following_params=SumoCarFollowingParams(speed_mode="obey_safe_speed"),
                 num_vehicles=13)
    vehicles.add(veh_id="rl", acceleration_controller=(RLController, {}),
                 routing_controller=(ContinuousRouter, {}),
                 car_following_params=SumoCarFollowingParams(speed_mode="obey_safe_speed"),
                 num_vehicles=1)  # fmt: skip
    return dict(
        exp_tag="adversarial_figure_eight", env_name=AdversarialAccelEnv,
        network=FigureEightNetwork, simulator="traci",
        sim=SumoParams(sim_step=0.1, render=False),
        env=EnvParams(horizon=horizon, additional_params={
            "target_velocity": 20, "max_accel": 3, "max_decel": 3, "perturb_weight": 0.03,
            "sort_vehicles": False}),
        net=NetParams(additional_params=deepcopy(ADDITIONAL_NET_PARAMS)),
        veh=vehicles, initial=InitialConfig(),
    )  # fmt: skip


@pytest.mark.sumo
def test_av_and_adversary_act_on_the_same_cars_with_opposite_rewards() -> None:
    create_env, _ = make_create_env(flow_params())
    env = create_env()
    try:
        obs_space, act_space = env.observation_space, env.action_space  # as Flow's example
        assert isinstance(obs_space, Box) and obs_space.shape == (28,)
        assert act_space.shape == (1,) and env.action_space("adversary") is act_space
        obs, _ = env.reset(seed=0)
        assert sorted(obs) == ["adversary", "av"]
        assert np.array_equal(obs["av"], obs["adversary"])
        applied: list[tuple[list[str], np.ndarray]] = []
        vk = env.k.vehicle
        real = vk.apply_acceleration

        def spy(ids: Any, acc: Any) -> None:
            applied.append((list(ids), np.asarray(acc, dtype=float)))
            real(ids, acc)

        vk.apply_acceleration = spy  # type: ignore[method-assign]
        _, rewards, _, _, _ = env.step({"av": np.array([1.0]), "adversary": np.array([-2.0])})
        assert applied[0][0] == ["rl_0"]
        assert applied[0][1] == pytest.approx([1.0 + 0.03 * -2.0])
        assert rewards["adversary"] == pytest.approx(-rewards["av"]) and rewards["av"] > 0
    finally:
        env.close()
    from pettingzoo.test import parallel_api_test

    env = create_env()
    try:
        parallel_api_test(env, num_cycles=20)
    finally:
        env.close()
