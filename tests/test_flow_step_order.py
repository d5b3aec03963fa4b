"""Flow's own step order works: ``apply_*``, then ``k.simulation.simulation_step()``, then
``k.vehicle.update(False)`` gives the commanded speeds and lanes (real SUMO)."""

from __future__ import annotations

import numpy as np
import pytest

from flowrun.envs.factory import make_env
from tests.conftest import load

pytestmark = pytest.mark.sumo


def test_accelerations_applied_before_a_bare_simulation_step_take_effect() -> None:
    env = make_env(load("sugiyama"))
    try:
        env.reset(seed=0)
        k = env.k
        for _ in range(20):
            env.step(None)
        ids = k.vehicle.get_ids()
        v0 = np.array(k.vehicle.get_speed(ids))
        accel = np.linspace(-0.5, 0.5, len(ids))
        k.vehicle.apply_acceleration(ids, accel)
        k.simulation.simulation_step()
        k.vehicle.update(False)
        expected = np.maximum(v0 + accel * k.simulation.sim_step, 0.0)
        assert np.array(k.vehicle.get_speed(ids)) == pytest.approx(expected, abs=1e-9)
    finally:
        env.close()


def test_lane_change_directions_other_than_minus_one_zero_one_are_refused() -> None:
    env = make_env(load("sugiyama"))
    try:
        env.reset(seed=0)
        vid = env.k.vehicle.get_ids()[0]
        for bad in (2, 3, -2):
            with pytest.raises(ValueError, match="-1, 0, or 1"):
                env.k.vehicle.apply_lane_change(vid, bad)
        env.k.vehicle.apply_lane_change(vid, 1)  # accepted (one lane: nothing to do)
    finally:
        env.close()


def test_a_vehicles_flow_controller_gives_the_groups_vectorised_acceleration() -> None:
    env = make_env(load("sugiyama"))
    try:
        env.reset(seed=0)
        for _ in range(50):
            env.step(None)
        vk = env.k.vehicle
        control = env.controls[0]
        expected = control.controller.get_accel(vk.inputs(control.sl, 0.0), env._ctrl_rng)
        for i in (0, 7, 21):
            vid = vk.get_ids()[i]
            ctrl = vk.get_acc_controller(vid)
            assert ctrl.veh_id == vid
            assert ctrl.get_action(env) == pytest.approx(expected[i], abs=1e-9)
        assert vk.get_routing_controller(vid).registered_name == "ContinuousRouter"
        assert vk.get_lane_changing_controller(vid).commands_sumo is False
    finally:
        env.close()


def test_tuple_actions_are_clipped_part_by_part() -> None:
    import gymnasium

    env = make_env(load("sugiyama"))
    try:
        space = gymnasium.spaces.Tuple(
            (gymnasium.spaces.Box(-1.0, 1.0, (2,)), gymnasium.spaces.Discrete(3))
        )
        env._space_cache = (space, env._spaces()[1])
        clipped = env.clip_actions((np.array([-5.0, 0.5]), 2))
        assert clipped[0] == pytest.approx([-1.0, 0.5])
        assert clipped[1] == 2
    finally:
        env.close()


def test_flows_older_module_paths_import_the_same_classes() -> None:
    from flowrun.envs import AccelEnv, LaneChangeAccelEnv, WaveAttenuationPOEnv
    from flowrun.envs.loop.lane_changing import LaneChangeAccelEnv as OldLC
    from flowrun.envs.loop.loop_accel import AccelEnv as OldAccel
    from flowrun.envs.loop.wave_attenuation import WaveAttenuationPOEnv as OldWave
    from flowrun.networks import FigureEightNetwork, HighwayNetwork, MergeNetwork
    from flowrun.scenarios.figure_eight import Figure8Scenario
    from flowrun.scenarios.highway import HighwayScenario
    from flowrun.scenarios.merge import MergeScenario

    assert (OldAccel, OldWave, OldLC) == (AccelEnv, WaveAttenuationPOEnv, LaneChangeAccelEnv)
    assert (Figure8Scenario, HighwayScenario, MergeScenario) == (
        FigureEightNetwork, HighwayNetwork, MergeNetwork,
    )  # fmt: skip


def test_tailway_on_the_ring_is_the_followers_headway() -> None:
    env = make_env(load("sugiyama"))
    try:
        env.reset(seed=0)
        for _ in range(30):
            env.step(None)
        vk = env.k.vehicle
        for vid in vk.get_ids()[:5]:
            follower = vk.get_follower(vid)
            assert vk.get_tailway(vid) == pytest.approx(vk.get_headway(follower))
    finally:
        env.close()


def test_flows_test_hooks_overwrite_leader_follower_and_headway_until_the_next_step() -> None:
    env = make_env(load("sugiyama"))
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        a, _, c = vk.get_ids()[:3]
        vk.set_follower(a, c)
        vk.set_leader(a, None)
        vk.set_headway(c, 12.5)
        assert (vk.get_follower(a), vk.get_leader(a), vk.get_headway(c)) == (c, None, 12.5)
        env.step(None)
        assert vk.get_follower(a) != c or vk.get_leader(a) is not None
    finally:
        env.close()


def test_rendered_runs_colour_rl_observed_and_other_cars_as_flow() -> None:
    cfg = load("ring_wave", "sim.render=true", "env.warmup_steps=0")
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        human = vk.get_human_ids()[0]
        vk.set_observed(human)
        env.step(np.zeros(1))
        for vid in vk.get_ids():
            expected = (255, 0, 0) if vid in vk.get_rl_ids() else (
                (0, 255, 255) if vid == human else (255, 255, 255)
            )
            assert vk.get_color(vid) == expected
        assert vk.get_observed_ids() == []  # marks last one step
    finally:
        env.close()


def test_flows_starting_positions_and_old_scenario_names() -> None:
    from flowrun.config.params import InitialConfig
    from flowrun.networks.base import Network
    from flowrun.scenarios import Scenario

    assert Scenario is Network
    env = make_env(load("sugiyama"))
    try:
        assert env.k.scenario is env.k.network  # before the first reset too
        pos, lanes = env.k.network.generate_starting_positions(
            initial_config=InitialConfig(), num_vehicles=4
        )
        # 4 cars evenly over the 230 m ring (no bunching): 57.5 m apart
        starts = env.k.network.total_edgestarts_dict
        x = [starts[e] + p for e, p in pos]
        assert np.diff(x) == pytest.approx([57.5] * 3)
        assert lanes == [0, 0, 0, 0]
    finally:
        env.close()
