"""The YAML is a view of the parameter objects: dumping and loading gives back an equal config."""

from __future__ import annotations

import math
from pathlib import Path

import yaml

from flowrun.config import (
    ControllerSpec,
    EnvParams,
    ExperimentConfig,
    InFlows,
    InitialConfig,
    NetParams,
    NetworkConfig,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    TrainConfig,
    VehicleParams,
    config_to_dict,
    dump_config,
)
from flowrun.controllers import ContinuousRouter, IDMController, RLController
from flowrun.loading import config_from_dict, load_config


def flow_style_config() -> ExperimentConfig:
    """A config written the way Flow's examples build ``flow_params``."""
    vehicles = VehicleParams()
    vehicles.add(
        veh_id="human",
        acceleration_controller=(IDMController, {"noise": 0.2}),
        routing_controller=(ContinuousRouter, {}),
        car_following_params=SumoCarFollowingParams(speed_mode="all_checks", min_gap=0),
        num_vehicles=21,
    )
    vehicles.add(
        veh_id="rl",
        acceleration_controller=(RLController, {}),
        routing_controller=(ContinuousRouter, {}),
        lane_change_params=SumoLaneChangeParams(lane_change_mode=0),
        num_vehicles=1,
        color="red",
    )
    return ExperimentConfig(
        name="ring_wave",
        sim=SumoParams(sim_step=0.1, seed=3, render=False, restart_instance=True),
        env=EnvParams(
            horizon=3000,
            warmup_steps=750,
            env_class="WaveAttenuationPOEnv",
            additional_params={"max_accel": 1, "max_decel": 1, "ring_length": [220, 270]},
        ),
        network=NetworkConfig(
            "ring",
            NetParams(additional_params={"length": 260, "lanes": 1, "speed_limit": 30}),
        ),
        vehicles=vehicles,
        initial=InitialConfig(bunching=20, spacing="uniform"),
        train=TrainConfig(
            algorithm="PPO",
            total_timesteps=20_000,
            n_envs=2,
            hyperparams={"n_steps": 128, "gamma": 0.999},
            policy_kwargs={"net_arch": [32, 32]},
        ),
    )


def test_flow_style_controller_tuples_become_controller_specs() -> None:
    groups = flow_style_config().vehicles.groups
    assert groups[0].acceleration_controller == ControllerSpec("IDM", {"noise": 0.2})
    assert groups[1].acceleration_controller.type == "RLController"


def test_dict_round_trip_of_a_python_built_config() -> None:
    cfg = flow_style_config()
    assert config_from_dict(config_to_dict(cfg)) == cfg


def test_yaml_round_trip_of_a_python_built_config(tmp_path: Path) -> None:
    cfg = flow_style_config()
    path = tmp_path / "dumped.yaml"
    path.write_text(dump_config(cfg))
    assert load_config(path) == cfg


def test_round_trip_of_defaults_keeps_infinities(tmp_path: Path) -> None:
    cfg = ExperimentConfig(name="defaults")
    text = dump_config(cfg)
    assert "horizon: .inf" in text and "lanes_distribution: .inf" in text
    path = tmp_path / "d.yaml"
    path.write_text(text)
    loaded = load_config(path)
    assert loaded == cfg and math.isinf(loaded.env.horizon)


def test_dump_uses_yaml_keys_and_flattens_network_and_controllers() -> None:
    data = config_to_dict(flow_style_config())
    assert data["sim"]["step"] == 0.1 and "sim_step" not in data["sim"]
    assert data["env"]["class"] == "WaveAttenuationPOEnv"
    assert data["network"] == {"type": "ring", "length": 260, "lanes": 1, "speed_limit": 30}
    human = data["vehicles"][0]
    assert human["id"] == "human" and human["count"] == 21
    assert human["acceleration_controller"] == {"type": "IDM", "noise": 0.2}
    assert human["car_following"]["speed_mode"] == "all_checks"
    assert list(data) == ["name", "sim", "env", "network", "vehicles", "initial", "train"]


def test_config_without_training_dumps_no_train_section() -> None:
    assert "train" not in config_to_dict(ExperimentConfig(name="x"))


def test_inflows_round_trip(tmp_path: Path) -> None:
    inflows = InFlows()
    inflows.add(edge="bottom", veh_type="human", vehs_per_hour=1200, depart_speed="max")
    vehicles = VehicleParams()
    vehicles.add("human", num_vehicles=0)
    cfg = ExperimentConfig(
        name="x",
        network=NetworkConfig("ring", NetParams(inflows=inflows)),
        vehicles=vehicles,
    )
    data = config_to_dict(cfg)
    assert data["network"]["inflows"][0]["vehs_per_hour"] == 1200
    assert config_from_dict(yaml.safe_load(dump_config(cfg))) == cfg


def test_dumped_yaml_file_loads_back_equal(tmp_path: Path) -> None:
    first = tmp_path / "sugiyama.yaml"
    first.write_text(
        "name: sugiyama\n"
        "network: {type: ring, length: 230}\n"
        "vehicles:\n"
        "  - {id: idm, count: 22, acceleration_controller: IDM,\n"
        "     routing_controller: {type: ContinuousRouter}}\n"
        "initial: {bunching: 20}\n"
    )
    cfg = load_config(first)
    second = tmp_path / "resolved.yaml"
    second.write_text(dump_config(cfg))
    assert load_config(second) == cfg
