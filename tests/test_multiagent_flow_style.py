"""A multi-agent env written Flow's way: a subclass of ``flowrun.envs.multiagent.base.MultiEnv``
with ``observation_space``/``action_space`` properties and dict ``get_state``,
``compute_reward`` and ``_apply_rl_actions``. Its spaces read both as Flow's properties and
as PettingZoo's methods, and it passes PettingZoo's parallel API test (real SUMO)."""

from __future__ import annotations

import pickle
from typing import Any

import numpy as np
import pytest
from gymnasium.spaces import Box
from pettingzoo.test import parallel_api_test

from flowrun.controllers import ContinuousRouter, IDMController, RLController
from flowrun.core.params import EnvParams, VehicleParams
from flowrun.envs.multiagent.base import MultiEnv
from flowrun.utils.registry import env_constructor
from tests.test_flow_params import ring_params


class SpeedAgents(MultiEnv):
    """Each AV sees its speed and its leader's; reward: its own speed; action: acceleration."""

    @property
    def observation_space(self) -> Box:
        return Box(low=0.0, high=50.0, shape=(2,), dtype=np.float32)

    @property
    def action_space(self) -> Box:
        return Box(low=-1.0, high=1.0, shape=(1,), dtype=np.float32)

    def get_state(self) -> dict[str, Any]:
        vk = self.k.vehicle
        return {
            rl_id: np.array([vk.get_speed(rl_id), vk.get_speed(vk.get_leader(rl_id) or rl_id)])
            for rl_id in vk.get_rl_ids()
        }

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> dict[str, float]:
        vk = self.k.vehicle
        return {rl_id: float(vk.get_speed(rl_id)) for rl_id in vk.get_rl_ids()}

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        self.applied = dict(rl_actions)
        ids = list(rl_actions)
        self.k.vehicle.apply_acceleration(ids, [float(rl_actions[i][0]) for i in ids])


def make() -> SpeedAgents:
    vehicles = VehicleParams()
    vehicles.add(veh_id="rl", acceleration_controller=(RLController, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=2)
    vehicles.add(veh_id="idm", acceleration_controller=(IDMController, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=12)  # fmt: skip
    params = ring_params(env_name=SpeedAgents, veh=vehicles, env=EnvParams(horizon=40))
    env: SpeedAgents = env_constructor(params)()
    return env


def test_spaces_read_as_flows_properties_and_pettingzoos_methods() -> None:
    env = make()
    try:
        box = env.observation_space
        assert isinstance(box, Box) and box.shape == (2,)
        assert env.observation_space("rl_0") is box and env.observation_space("rl_1") is box
        assert env.action_space("rl_1") is env.action_space and env.action_space.shape == (1,)
        again = pickle.loads(pickle.dumps(box))  # Ray ships spaces to its workers
        assert again == box and again("rl_0") is again
    finally:
        env.close()


@pytest.mark.sumo
def test_dict_states_rewards_and_actions_flow_through_the_parallel_api() -> None:
    env = make()
    try:
        obs, _ = env.reset(seed=0)
        assert sorted(obs) == ["rl_0", "rl_1"] and obs["rl_0"].shape == (2,)
        actions = {"rl_0": np.array([1.0]), "rl_1": np.array([0.5])}
        obs, rewards, terms, truncs, _ = env.step(actions)
        assert sorted(env.applied) == ["rl_0", "rl_1"]
        assert env.applied["rl_1"][0] == pytest.approx(0.5)
        vk = env.k.vehicle
        assert rewards["rl_0"] == pytest.approx(vk.get_speed("rl_0"))
        assert not any(terms.values()) and not any(truncs.values())
    finally:
        env.close()
    env = make()
    try:
        parallel_api_test(env, num_cycles=30)
    finally:
        env.close()
