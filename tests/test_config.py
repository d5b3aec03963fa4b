"""Loading YAML configs: defaults, accepted spellings, and located errors for every mistake."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import pytest

from flowrun.config import (
    ControllerSpec,
    ExperimentConfig,
    SumoParams,
    TrainConfig,
    VehicleParams,
    VehicleType,
)
from flowrun.errors import ConfigError
from flowrun.loading import config_from_dict, load_config

SUGIYAMA = """\
name: sugiyama
sim:        {step: 0.1, seed: 0, render: false}
env:        {horizon: 3000, warmup_steps: 0,
             additional_params: {max_accel: 1, max_decel: 1}}
network:    {type: ring, length: 230, lanes: 1, speed_limit: 30, resolution: 40}
vehicles:
  - {id: idm, count: 22,
     acceleration_controller: {type: IDM, v0: 30, T: 1, a: 1, b: 1.5, delta: 4, s0: 2, noise: 0},
     routing_controller: {type: ContinuousRouter}}
initial:    {spacing: uniform, bunching: 20, perturbation: 0}
"""


def write(tmp_path: Path, text: str, name: str = "exp.yaml") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def load_error(tmp_path: Path, text: str) -> tuple[ConfigError, str]:
    """The error of loading ``text``, and the file name its location should start with."""
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    return info.value, str(path)


# --- what loads ---------------------------------------------------------------------------


def test_sugiyama_yaml_loads_into_flow_parameter_objects(tmp_path: Path) -> None:
    cfg = load_config(write(tmp_path, SUGIYAMA))
    assert cfg.name == "sugiyama"
    assert cfg.sim.sim_step == 0.1 and cfg.sim.seed == 0
    assert type(cfg.env.horizon) is int  # a step count, though .inf is allowed
    assert cfg.env.horizon == 3000 and cfg.env.additional_params == {"max_accel": 1, "max_decel": 1}
    assert cfg.network.type == "ring"
    assert cfg.network.net_params.additional_params == {
        "length": 230,
        "lanes": 1,
        "speed_limit": 30,
        "resolution": 40,
    }
    (group,) = cfg.vehicles.groups
    assert (group.veh_id, group.num_vehicles) == ("idm", 22)
    assert group.acceleration_controller == ControllerSpec(
        "IDM", {"v0": 30, "T": 1, "a": 1, "b": 1.5, "delta": 4, "s0": 2, "noise": 0}
    )
    assert group.routing_controller == ControllerSpec("ContinuousRouter")
    assert cfg.vehicles.num_vehicles == 22
    assert cfg.initial.bunching == 20.0 and cfg.initial.spacing == "uniform"
    assert cfg.train is None


def test_omitted_sections_are_flow_defaults_and_name_defaults_to_file_stem(
    tmp_path: Path,
) -> None:
    text = "network: {type: ring}\nvehicles: [{id: a, count: 2}]\n"
    cfg = load_config(write(tmp_path, text, name="ring_wave.yaml"))
    assert cfg == ExperimentConfig(
        name="ring_wave", vehicles=VehicleParams([VehicleType("a", num_vehicles=2)])
    )


def test_an_empty_config_file_is_refused_with_its_name(tmp_path: Path) -> None:
    for text in ("", "# only a comment\n", "---\n"):
        path = write(tmp_path, text, name="empty.yaml")
        with pytest.raises(ConfigError, match="empty") as err:
            load_config(path)
        assert err.value.location == str(path)


def test_empty_section_means_defaults_but_empty_train_means_no_training(
    tmp_path: Path,
) -> None:
    cfg = load_config(write(tmp_path, "name: x\nsim:\nenv:\ntrain:\nnetwork: {type: ring}\n"))
    assert cfg == ExperimentConfig(name="x")


def test_field_names_are_accepted_where_yaml_keys_differ(tmp_path: Path) -> None:
    cfg = load_config(
        write(
            tmp_path,
            """\
            name: x
            network: {type: ring}
            sim: {sim_step: 0.2}
            env: {env_class: my_envs:MyEnv}
            vehicles:
              - {veh_id: a, num_vehicles: 2, car_following_params: {speed_mode: all_checks}}
            """,
        )
    )
    assert cfg.sim.sim_step == 0.2
    assert cfg.env.env_class == "my_envs:MyEnv"
    assert cfg.vehicles.groups[0].num_vehicles == 2
    assert cfg.vehicles.groups[0].car_following_params.speed_mode == 31


def test_bare_controller_name_and_inf_and_int_for_float(tmp_path: Path) -> None:
    cfg = load_config(
        write(
            tmp_path,
            """\
            name: x
            network: {type: ring}
            sim: {step: 1}
            env: {horizon: .inf}
            initial: {lanes_distribution: .inf}
            vehicles: [{id: a, count: 1, acceleration_controller: IDM}]
            """,
        )
    )
    assert cfg.sim.sim_step == 1.0 and isinstance(cfg.sim.sim_step, float)
    assert math.isinf(cfg.env.horizon) and math.isinf(cfg.initial.lanes_distribution)
    assert cfg.vehicles.groups[0].acceleration_controller == ControllerSpec("IDM")


def test_train_section_keeps_hyperparams_and_policy_kwargs_free(tmp_path: Path) -> None:
    cfg = load_config(
        write(
            tmp_path,
            """\
            name: x
            network: {type: ring}
            train:
              algorithm: PPO
              total_timesteps: 5000
              hyperparams: {n_steps: 128, anything_sb3_takes: 1}
              policy_kwargs: {net_arch: [32, 32]}
            """,
        )
    )
    assert cfg.train == TrainConfig(
        total_timesteps=5000,
        hyperparams={"n_steps": 128, "anything_sb3_takes": 1},
        policy_kwargs={"net_arch": [32, 32]},
    )


def test_config_from_dict_uses_the_same_schema() -> None:
    cfg = config_from_dict({"name": "x", "sim": {"step": 0.5}, "network": {"type": "ring"}})
    assert cfg == ExperimentConfig(name="x", sim=SumoParams(sim_step=0.5))
    with pytest.raises(ConfigError) as info:
        config_from_dict({"name": "x", "sim": {"stpe": 0.5}}, source="flow_params")
    assert info.value.location == "flow_params"
    assert info.value.path == "sim.stpe"


# --- file and YAML errors -------------------------------------------------------------------


def test_missing_file_is_a_clear_error(tmp_path: Path) -> None:
    path = tmp_path / "nope.yaml"
    with pytest.raises(ConfigError, match="config file not found") as info:
        load_config(path)
    assert info.value.location == str(path)


def test_yaml_syntax_error_names_the_line_pyyaml_reports(tmp_path: Path) -> None:
    err, file = load_error(tmp_path, "name: x\nsim: {step: 0.1\nenv: {horizon: 3}\n")
    assert err.location == f"{file}:3"
    assert "invalid YAML" in err.message


def test_duplicate_key_in_one_mapping_is_an_error(tmp_path: Path) -> None:
    err, file = load_error(tmp_path, "name: x\nsim:\n  step: 0.1\n  seed: 1\n  step: 0.2\n")
    assert err.location == f"{file}:5"
    assert err.path == "sim.step"
    assert "duplicate key 'step' (first given on line 3)" in err.message


def test_top_level_must_be_a_mapping(tmp_path: Path) -> None:
    err, file = load_error(tmp_path, "- name: x\n")
    assert err.location == f"{file}:1"
    assert "expected a mapping" in err.message


# --- unknown keys ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "line", "path", "hint"),
    [
        ("name: x\nvehicle: []\n", 2, "vehicle", "did you mean 'vehicles'?"),
        ("name: x\nsim:\n  seed: 1\n  stpe: 0.1\n", 4, "sim.stpe", "did you mean 'step'?"),
        (
            "name: x\nvehicles:\n  - id: a\n    cuont: 3\n",
            4,
            "vehicles[0].cuont",
            "did you mean 'count'?",
        ),
        (
            "name: x\nvehicles:\n  - id: a\n    car_following:\n      speed_mod: aggressive\n",
            5,
            "vehicles[0].car_following.speed_mod",
            "did you mean 'speed_mode'?",
        ),
        ("name: x\ntrain:\n  n_env: 2\n", 3, "train.n_env", "did you mean 'n_envs'?"),
        (
            "name: x\nnetwork:\n  type: ring\n  lenght: 230\n",
            4,
            "network.lenght",
            "did you mean 'length'?",
        ),
    ],
)
def test_unknown_key_is_located_with_did_you_mean(
    tmp_path: Path, text: str, line: int, path: str, hint: str
) -> None:
    err, file = load_error(tmp_path, text)
    assert err.location == f"{file}:{line}"
    assert err.path == path
    assert hint in err.message


def test_same_setting_under_yaml_key_and_field_name_is_an_error(tmp_path: Path) -> None:
    err, file = load_error(tmp_path, "name: x\nsim:\n  step: 0.1\n  sim_step: 0.2\n")
    assert (err.location, err.path) == (f"{file}:4", "sim.sim_step")
    assert "same setting" in err.message


def test_missing_required_vehicle_id(tmp_path: Path) -> None:
    err, file = load_error(tmp_path, "name: x\nvehicles:\n  - count: 3\n")
    assert (err.location, err.path) == (f"{file}:3", "vehicles[0]")
    assert "missing required key 'id'" in err.message


# --- wrong types ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "line", "path", "message"),
    [
        (
            "name: x\nvehicles:\n  - id: a\n    count: many\n",
            4,
            "vehicles[0].count",
            "expected an integer, got 'many'",
        ),
        (
            "name: x\nvehicles:\n  - id: a\n    count: true\n",
            4,
            "vehicles[0].count",
            "expected an integer, got true",
        ),
        ("name: x\nsim:\n  step: fast\n", 3, "sim.step", "expected a number, got 'fast'"),
        ("name: x\nsim:\n  render: 1\n", 3, "sim.render",
         "expected true or false or a string, got 1"),
        ("name: x\nsim: [1, 2]\n", 2, "sim", "expected a mapping of settings, got a list"),
        ("name: x\nvehicles: {id: a}\n", 2, "vehicles", "expected a list of vehicle groups"),
        (
            "name: x\nenv:\n  additional_params: 3\n",
            3,
            "env.additional_params",
            "expected a mapping, got 3",
        ),
        (
            "name: x\nvehicles:\n  - id: a\n    acceleration_controller: 3\n",
            4,
            "vehicles[0].acceleration_controller",
            "expected a controller name or a mapping with 'type', got 3",
        ),
        (
            "name: x\nvehicles:\n  - id: a\n    acceleration_controller: {v0: 3}\n",
            4,
            "vehicles[0].acceleration_controller",
            "missing required key 'type'",
        ),
    ],
)
def test_wrong_type_is_located(
    tmp_path: Path, text: str, line: int, path: str, message: str
) -> None:
    err, file = load_error(tmp_path, text)
    assert err.location == f"{file}:{line}"
    assert err.path == path
    assert message in err.message


# --- impossible values ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "line", "path", "message"),
    [
        ("name: x\nsim:\n  step: -0.1\n", 3, "sim.step", "must be greater than 0, got -0.1"),
        ("name: x\nsim:\n  step: 0\n", 3, "sim.step", "must be greater than 0, got 0"),
        ("name: x\nenv:\n  horizon: 0\n", 3, "env.horizon", "must be greater than 0, got 0"),
        ("name: x\nenv:\n  warmup_steps: -1\n", 3, "env.warmup_steps", "at least 0, got -1"),
        ("name: x\nenv:\n  sims_per_step: 0\n", 3, "env.sims_per_step", "at least 1, got 0"),
        (
            "name: x\nnetwork:\n  type: ring\n  length: -5\n",
            4,
            "network.length",
            "must be greater than 0, got -5",
        ),
        (
            "name: x\nvehicles:\n  - id: a\n    count: -1\n",
            4,
            "vehicles[0].count",
            "at least 0, got -1",
        ),
        (
            "name: x\ninitial:\n  spacing: unifrom\n",
            3,
            "initial.spacing",
            "unknown spacing 'unifrom' (did you mean 'uniform'?)",
        ),
        (
            "name: x\nvehicles:\n  - id: a\n    car_following: {speed_mode: agressive}\n",
            4,
            "vehicles[0].car_following.speed_mode",
            "unknown speed_mode 'agressive' (did you mean 'aggressive'?)",
        ),
        (
            "name: x\nvehicles:\n  - id: a\n    lane_change:\n      lane_change_mode: no_lc_saf\n",
            5,
            "vehicles[0].lane_change.lane_change_mode",
            "unknown lane_change_mode 'no_lc_saf' (did you mean 'no_lc_safe'?)",
        ),
        (
            "name: x\ntrain:\n  algorithm: PPOO\n",
            3,
            "train.algorithm",
            "unknown algorithm 'PPOO' (did you mean 'PPO'?)",
        ),
        ("name: a/b\n", 1, "name", "must not contain '/'"),
    ],
)
def test_impossible_value_is_located(
    tmp_path: Path, text: str, line: int, path: str, message: str
) -> None:
    err, file = load_error(tmp_path, text)
    assert err.location == f"{file}:{line}"
    assert err.path == path
    assert message in err.message


def test_int_speed_mode_is_accepted(tmp_path: Path) -> None:
    cfg = load_config(
        write(tmp_path, "name: x\nnetwork: {type: ring}\n"
              "vehicles: [{id: a, car_following: {speed_mode: 7}}]\n")
    )
    assert cfg.vehicles.groups[0].car_following_params.speed_mode == 7


def test_duplicate_vehicle_group_ids(tmp_path: Path) -> None:
    err, file = load_error(
        tmp_path,
        "name: x\nvehicles:\n  - id: human\n    count: 1\n  - count: 1\n    id: human\n",
    )
    assert (err.location, err.path) == (f"{file}:6", "vehicles[1].id")
    assert "duplicate vehicle group id 'human' (also vehicles[0])" in err.message


def test_inflow_of_unknown_vehicle_group(tmp_path: Path) -> None:
    err, file = load_error(
        tmp_path,
        """\
        name: x
        network:
          type: ring
          inflows:
            - {edge: bottom, veh_type: humna, vehs_per_hour: 100}
        vehicles: [{id: human}]
        """,
    )
    assert (err.location, err.path) == (f"{file}:5", "network.inflows[0].veh_type")
    assert "did you mean 'human'?" in err.message


def test_yaml_anchors_and_merge_keys_work(tmp_path: Path) -> None:
    cfg = load_config(
        write(
            tmp_path,
            "name: x\nnetwork: {type: ring}\nvehicles:\n  - &h {id: a, count: 2}\n"
            "  - {<<: *h, id: b}\n",
        )
    )
    assert [(g.veh_id, g.num_vehicles) for g in cfg.vehicles.groups] == [("a", 2), ("b", 2)]


def test_recursive_alias_is_an_error(tmp_path: Path) -> None:
    err, file = load_error(tmp_path, "name: x\nenv:\n  additional_params: &a\n    k: *a\n")
    assert (err.location, err.path) == (f"{file}:3", "env.additional_params.k")
