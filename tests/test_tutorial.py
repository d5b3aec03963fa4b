"""Flow's tutorial "Creating custom environments" runs on flowrun with only its imports changed.

The module-level code below is the tutorial's code blocks in order, as written, with
``flow.`` -> ``flowrun.`` and ``gym.spaces`` -> ``gymnasium.spaces`` (``tuple_space.Tuple`` is
``gymnasium.spaces.Tuple``). The tutorial's ``from flow.envs import myEnv`` step (editing
Flow's ``envs/__init__.py``) is not needed: a config names the class by import path
(``tests/test_custom_env.py``). The rllab training block is replaced by its environment setup;
training is ``flowrun train``.
"""
# ruff: noqa: E402, I001

# ---------------------------------------------------------------- tutorial, section 1
# import the base environment class
from flowrun.envs import Env


# define the environment class, and inherit properties from the base environment class
class myEnv(Env):
    pass


ADDITIONAL_ENV_PARAMS = {
    "max_accel": 1,
    "max_decel": 1,
}

from gymnasium.spaces.box import Box

from gymnasium.spaces import Tuple  # noqa: F401 - the tutorial imports it without using it


class myEnv(myEnv):
    @property
    def action_space(self):
        num_actions = self.initial_vehicles.num_rl_vehicles
        accel_ub = self.env_params.additional_params["max_accel"]
        accel_lb = - abs(self.env_params.additional_params["max_decel"])

        return Box(low=accel_lb,
                   high=accel_ub,
                   shape=(num_actions,))


class myEnv(myEnv):  # update my environment class
    @property
    def observation_space(self):
        return Box(
            low=0,
            high=float("inf"),
            shape=(2*self.initial_vehicles.num_vehicles,),
        )


class myEnv(myEnv):  # update my environment class
    def _apply_rl_actions(self, rl_actions):
        # the names of all autonomous (RL) vehicles in the network
        rl_ids = self.k.vehicle.get_rl_ids()

        # use the base environment method to convert actions into accelerations for the rl vehicles
        self.k.vehicle.apply_acceleration(rl_ids, rl_actions)


import numpy as np


class myEnv(myEnv):  # update my environment class
    def get_state(self, **kwargs):
        # the get_ids() method is used to get the names of all vehicles in the network
        ids = self.k.vehicle.get_ids()

        # we use the get_absolute_position method to get the positions of all vehicles
        pos = [self.k.vehicle.get_x_by_id(veh_id) for veh_id in ids]

        # we use the get_speed method to get the velocities of all vehicles
        vel = [self.k.vehicle.get_speed(veh_id) for veh_id in ids]

        # the speeds and positions are concatenated to produce the state
        return np.concatenate((pos, vel))


import numpy as np  # noqa: F811 - the tutorial imports it again


class myEnv(myEnv):  # update my environment class
    def compute_reward(self, rl_actions, **kwargs):
        # the get_ids() method is used to get the names of all vehicles in the network
        ids = self.k.vehicle.get_ids()

        # we next get a list of the speeds of all vehicles in the network
        speeds = self.k.vehicle.get_speed(ids)

        # finally, we return the average of all these speeds as the reward
        return np.mean(speeds)


# ---------------------------------------------------------------- tutorial, section 2
from flowrun.controllers import IDMController, ContinuousRouter
from flowrun.core.experiment import Experiment
from flowrun.core.params import SumoParams, EnvParams, \
    InitialConfig, NetParams
from flowrun.core.params import VehicleParams
from flowrun.scenarios.loop import LoopScenario, ADDITIONAL_NET_PARAMS


def tutorial_simulation():
    """The tutorial's non-RL run: 22 IDM cars, ``Experiment(env).run(1, 1500)``."""
    sumo_params = SumoParams(sim_step=0.1, render=True)

    vehicles = VehicleParams()
    vehicles.add(veh_id="idm",
                 acceleration_controller=(IDMController, {}),
                 routing_controller=(ContinuousRouter, {}),
                 num_vehicles=22)

    env_params = EnvParams(additional_params=ADDITIONAL_ENV_PARAMS)

    additional_net_params = ADDITIONAL_NET_PARAMS.copy()
    net_params = NetParams(additional_params=additional_net_params)

    initial_config = InitialConfig(bunching=20)

    scenario = LoopScenario(name="sugiyama",
                            vehicles=vehicles,
                            net_params=net_params,
                            initial_config=initial_config)

    #############################################################
    ######## using my new environment for the simulation ########
    #############################################################
    env = myEnv(env_params, sumo_params, scenario)
    #############################################################

    exp = Experiment(env)

    _ = exp.run(1, 1500)
    return env, exp, _


from flowrun.controllers import RLController

HORIZON = 1500


def tutorial_training_env():
    """The environment of the tutorial's ``run_task`` (1 RL car, 21 IDM), without rllab."""
    sumo_params = SumoParams(sim_step=0.1, render=False)

    vehicles = VehicleParams()
    vehicles.add(veh_id="rl",
                 acceleration_controller=(RLController, {}),
                 routing_controller=(ContinuousRouter, {}),
                 num_vehicles=1)
    vehicles.add(veh_id="idm",
                 acceleration_controller=(IDMController, {}),
                 routing_controller=(ContinuousRouter, {}),
                 num_vehicles=21)

    env_params = EnvParams(horizon=HORIZON,
                           additional_params=ADDITIONAL_ENV_PARAMS)

    additional_net_params = ADDITIONAL_NET_PARAMS.copy()
    net_params = NetParams(additional_params=additional_net_params)

    initial_config = InitialConfig(bunching=20)

    scenario = LoopScenario(name="sugiyama-training",
                            vehicles=vehicles,
                            net_params=net_params,
                            initial_config=initial_config)

    return myEnv(env_params, sumo_params, scenario)


# ---------------------------------------------------------------- the checks
import logging
from pathlib import Path

import libsumo
import pytest

from flowrun.loading.loader import load_config
from flowrun.experiment.baseline import run_baseline
from flowrun.recording.reader import open_log

SUGIYAMA = Path(__file__).resolve().parent.parent / "configs" / "sugiyama.yaml"

pytestmark = pytest.mark.sumo


def sumo_state(env):
    """Ring position and speed of every car, read from SUMO itself (not the kernel)."""
    ids = env.k.vehicle.get_ids()
    pos = [env.k.network.get_x(libsumo.vehicle.getRoadID(v), libsumo.vehicle.getLanePosition(v))
           for v in ids]
    return np.array(pos), np.array([libsumo.vehicle.getSpeed(v) for v in ids])


@pytest.fixture(scope="module")
def headless(request):
    """Run the tutorial with no display, as on a server or in CI."""
    mp = pytest.MonkeyPatch()
    mp.delenv("DISPLAY", raising=False)
    mp.delenv("WAYLAND_DISPLAY", raising=False)
    request.addfinalizer(mp.undo)


class Records(logging.Handler):
    """Keeps the log records of the ``flowrun`` loggers."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.records = []

    def emit(self, record):
        self.records.append(record)


@pytest.fixture(scope="module")
def tutorial_run(headless):
    handler = Records()
    logger = logging.getLogger("flowrun")
    logger.addHandler(handler)
    try:
        env, exp, result = tutorial_simulation()
    finally:
        logger.removeHandler(handler)
    yield env, exp, result, handler.records
    env.close()


def test_render_true_without_display_runs_headless_and_warns(tutorial_run):
    env, _, _, records = tutorial_run
    assert env.sim_params.render is True
    assert env.k.gui is False
    warnings = [r.getMessage() for r in records if r.levelno == logging.WARNING]
    assert any("no display" in m and "headless" in m for m in warnings), warnings


def test_experiment_runs_1500_steps_despite_infinite_horizon(tutorial_run):
    env, _, result, _ = tutorial_run
    assert env.env_params.horizon == float("inf")
    assert len(result["per_step_returns"]) == 1
    assert len(result["per_step_returns"][0]) == 1500
    assert env.k.simulation.time == pytest.approx(150.2)  # start + insertion + 1500 steps
    assert result["returns"][0] == pytest.approx(sum(result["per_step_returns"][0]))


def test_all_idm_spaces_have_no_action_and_two_values_per_car(tutorial_run):
    env, _, _, _ = tutorial_run
    assert env.action_space.shape == (0,)
    assert env.observation_space.shape == (44,)
    assert env.initial_vehicles.num_vehicles == 22
    assert env.initial_vehicles.num_rl_vehicles == 0


def test_get_state_is_positions_then_speeds_of_all_cars(tutorial_run):
    env, _, _, _ = tutorial_run
    state = env.get_state()
    pos, speed = sumo_state(env)
    assert state.shape == (44,)
    np.testing.assert_allclose(state[:22], pos, rtol=0, atol=1e-9)
    np.testing.assert_allclose(state[22:], speed, rtol=0, atol=1e-12)
    assert speed.max() > 0.5  # the cars are moving: the check compares real numbers


def test_reward_is_the_mean_speed(tutorial_run):
    env, _, result, _ = tutorial_run
    _, speed = sumo_state(env)
    assert result["per_step_returns"][0][-1] == pytest.approx(speed.mean(), abs=1e-12)
    assert env.compute_reward(None) == pytest.approx(speed.mean(), abs=1e-12)


def test_rl_setup_has_one_action_for_the_one_rl_car():
    env = tutorial_training_env()
    try:
        assert env.action_space.shape == (1,)
        assert env.observation_space.shape == (44,)
        obs, _ = env.reset(seed=0)
        assert obs.shape == (44,)
        rl = env.k.vehicle.get_rl_ids()
        assert rl == ["rl_0"]
        for _ in range(10):
            obs, reward, terminated, truncated, _ = env.step(np.array([1.0]))
        # accelerating at max_accel = 1 m/s^2 for 10 steps of 0.1 s from rest
        assert env.k.vehicle.get_speed("rl_0") == pytest.approx(1.0, abs=1e-9)
        assert not terminated and not truncated
        assert reward == pytest.approx(np.mean(obs[22:]))
    finally:
        env.close()


def test_all_idm_run_matches_flowrun_baseline_of_sugiyama_yaml(tutorial_run, tmp_path):
    env, exp, _, _ = tutorial_run
    speeds, positions = [], []

    def record(run, step):
        speeds.append(env.k.vehicle.speed.copy())
        positions.append(env.k.vehicle.position.copy())

    exp.progress = record
    try:
        exp.run(1, 1500)  # the tutorial's run again (same seed), now keeping every step
    finally:
        exp.progress = None
    baseline = run_baseline(load_config(SUGIYAMA), steps=1500, out=tmp_path)
    frames = list(open_log(baseline.logs[0]).frames())
    assert len(frames) == 1501  # state after reset, then one per step
    logged_speed = np.array([f.speed for f in frames[1:]])
    logged_pos = np.array([f.position for f in frames[1:]])
    assert [str(i) for i in frames[0].ids] == env.k.vehicle.get_ids()
    np.testing.assert_allclose(np.array(speeds), logged_speed, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.array(positions), logged_pos, rtol=0, atol=1e-9)
    # the trajectories are the stop-and-go ones, not a trivially equal standstill
    assert logged_speed[-1].min() < 1.0 < logged_speed[-1].max()
