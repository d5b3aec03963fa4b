"""Python parameter objects and YAML configs are one model: same values, same environment."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from flowrun.config.dump import dump_config
from flowrun.config.model import ExperimentConfig, NetworkConfig
from flowrun.controllers import ContinuousRouter, IDMController, RLController
from flowrun.core.params import (
    EnvParams,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoParams,
    VehicleParams,
)
from flowrun.envs import WaveAttenuationPOEnv
from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config
from flowrun.scenarios.loop import ADDITIONAL_NET_PARAMS, LoopScenario

RING_WAVE = Path(__file__).resolve().parent.parent / "configs" / "ring_wave.yaml"
IDM = {"v0": 30, "T": 1, "a": 1, "b": 1.5, "delta": 4, "s0": 2, "noise": 0.2}


def ring_wave_in_python() -> ExperimentConfig:
    """``configs/ring_wave.yaml`` written with Flow's Python objects."""
    vehicles = VehicleParams()
    vehicles.add(
        veh_id="human",
        acceleration_controller=(IDMController, dict(IDM)),
        routing_controller=(ContinuousRouter, {}),
        num_vehicles=21,
    )
    vehicles.add(
        veh_id="rl",
        acceleration_controller=(RLController, {}),
        routing_controller=(ContinuousRouter, {}),
        car_following_params=SumoCarFollowingParams(speed_mode="right_of_way"),
        num_vehicles=1,
    )
    return ExperimentConfig(
        name="ring_wave",
        sim=SumoParams(sim_step=0.1, seed=0, render=False),
        env=EnvParams(
            env_class="WaveAttenuationPOEnv",
            horizon=3000,
            warmup_steps=750,
            additional_params={"max_accel": 1, "max_decel": 1, "ring_length": [220, 270]},
        ),
        network=NetworkConfig("ring", NetParams(dict(ADDITIONAL_NET_PARAMS))),
        vehicles=vehicles,
        initial=InitialConfig(spacing="uniform", bunching=20, perturbation=0),
    )


def test_python_config_dumps_to_yaml_and_loads_back_equal(tmp_path):
    cfg = ring_wave_in_python()
    path = tmp_path / "ring_wave.yaml"
    path.write_text(dump_config(cfg))
    loaded = load_config(path)
    assert loaded == cfg
    assert loaded.vehicles.groups[0].acceleration_controller.type == "IDM"
    assert loaded.vehicles.groups[1].acceleration_controller.type == "RLController"
    assert loaded.vehicles.groups[0].routing_controller.type == "ContinuousRouter"
    again = tmp_path / "again.yaml"
    again.write_text(dump_config(loaded))
    assert dump_config(load_config(again)) == dump_config(loaded)  # a fixed point


def test_python_config_equals_the_shipped_yaml():
    shipped = load_config(RING_WAVE)
    assert replace(shipped, train=None) == ring_wave_in_python()


@pytest.mark.sumo
def test_python_objects_and_yaml_make_the_same_episode(tmp_path):
    cfg = replace(ring_wave_in_python(), env=replace(ring_wave_in_python().env, warmup_steps=50))
    path = tmp_path / "cfg.yaml"
    path.write_text(dump_config(cfg))
    scenario = LoopScenario(
        name=cfg.name,
        vehicles=cfg.vehicles,
        net_params=cfg.network.net_params,
        initial_config=cfg.initial,
    )
    episodes = []
    for make in (
        lambda: WaveAttenuationPOEnv(cfg.env, cfg.sim, scenario),
        lambda: make_env(load_config(path)),
    ):
        env = make()
        try:
            obs, _ = env.reset(seed=5)
            steps = [obs]
            for _ in range(30):
                obs, *_ = env.step(np.array([0.5], dtype=np.float32))
                steps.append(obs)
            episodes.append((env.k.network.length(), np.array(steps)))
        finally:
            env.close()
    (len_a, obs_a), (len_b, obs_b) = episodes
    assert len_a == len_b
    assert np.array_equal(obs_a, obs_b)


def test_loop_scenario_is_the_ring_network_under_both_flow_import_paths():
    from flowrun.networks.ring import LoopScenario as FromNetworks
    from flowrun.networks.ring import RingNetwork

    assert FromNetworks is RingNetwork and LoopScenario is RingNetwork
    assert ADDITIONAL_NET_PARAMS == {"length": 230, "lanes": 1, "speed_limit": 30, "resolution": 40}
