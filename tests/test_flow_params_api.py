"""Flow's parameter objects to the letter: mutable where Flow code mutates them, Flow's camelCase
keywords, Flow's fields and defaults, modes stored as SUMO's ints; ``flowrun validate``/``train``
on Flow config modules; Flow's example configs (``examples/flow_configs``) convert and run."""

from __future__ import annotations

import logging
import math
import runpy
import warnings
from pathlib import Path
from typing import Any

import pytest
import typer
import yaml
from typer.testing import CliRunner

from flowrun.config.validate import check_params
from flowrun.controllers import ContinuousRouter, IDMController, RLController
from flowrun.core.params import (
    EnvParams,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    VehicleParams,
)
from flowrun.errors import ConfigError
from flowrun.loading.flow_params import from_flow_params
from flowrun.loading.loader import load_config
from flowrun.networks.ring import RingNetwork

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "flow_configs"
NON_RL = ["ring", "figure_eight", "merge", "highway"]
RL = ["singleagent_ring", "singleagent_figure_eight", "singleagent_merge"]


def ring_flow_params() -> dict[str, Any]:
    vehicles = VehicleParams()
    vehicles.add("idm", acceleration_controller=(IDMController, {}),
                 routing_controller=(ContinuousRouter, {}), num_vehicles=22)  # fmt: skip
    return dict(
        exp_tag="ring", env_name="AccelEnv", network=RingNetwork, simulator="traci",
        sim=SumoParams(), env=EnvParams(horizon=1500, additional_params={
            "max_accel": 1, "max_decel": 1, "target_velocity": 10, "sort_vehicles": False}),
        net=NetParams(additional_params={"length": 230, "lanes": 1, "speed_limit": 30,
                                         "resolution": 40}),
        veh=vehicles, initial=InitialConfig(bunching=20),
    )  # fmt: skip


def camel(cls: type, **kwargs: Any) -> Any:
    """``cls(**kwargs)`` with Flow's deprecated keywords, checking the warning is given."""
    with pytest.warns(DeprecationWarning, match="Flow's deprecated spelling"):
        return cls(**kwargs)


# -- 1. mutable where Flow code mutates them -------------------------------------------------


def test_flow_code_can_mutate_the_params_and_the_experiment_sees_it() -> None:
    params = ring_flow_params()
    params["env"].horizon = 1000
    params["sim"].render = True
    params["sim"].sim_step = 0.2
    params["initial"].spacing = "random"
    params["net"].additional_params["length"] = 260
    params["veh"].type_parameters["idm"]["car_following_params"].min_gap = 1.0
    cfg = from_flow_params(params).config
    assert cfg.env.horizon == 1000 and cfg.sim.render and cfg.sim.sim_step == 0.2
    assert cfg.initial.spacing == "random"
    assert cfg.network.net_params.additional_params["length"] == 260
    assert cfg.vehicles.groups[0].car_following_params.min_gap == 1.0


def test_a_bad_value_set_after_construction_is_refused_where_it_is_used() -> None:
    params = ring_flow_params()
    params["env"].horizon = -5
    with pytest.raises(ConfigError, match=r"env.horizon: must be greater than 0, got -5"):
        from_flow_params(params)
    sim = SumoParams()
    sim.sim_step = 0
    with pytest.raises(ConfigError, match=r"sim.step: must be greater than 0"):
        check_params(sim, EnvParams(), InitialConfig())


def test_params_still_copy_and_replace() -> None:
    import copy
    import dataclasses

    cf = SumoCarFollowingParams(speed_mode="all_checks", min_gap=1)
    assert copy.deepcopy(cf) == cf
    assert dataclasses.replace(cf, speed_mode="aggressive").speed_mode == 0


# -- 2. Flow's keywords and fields -----------------------------------------------------------

CF_CAMEL = {"minGap": 1.0, "maxSpeed": 20, "speedFactor": 1.1, "speedDev": 0.2,
            "carFollowModel": "Krauss"}  # fmt: skip
CF_SNAKE = {"min_gap": 1.0, "max_speed": 20, "speed_factor": 1.1, "speed_dev": 0.2,
            "car_follow_model": "Krauss"}  # fmt: skip
LC_CAMEL = {"lcStrategic": 2.0, "lcCooperative": 0.5, "lcSpeedGain": 3.0, "lcKeepRight": 0.0,
            "lcLookaheadLeft": 1.5, "lcSpeedGainRight": 0.7, "lcSublane": 2.0, "lcPushy": 0.3,
            "lcPushyGap": 0.4, "lcAssertive": 2.0, "lcImpatience": 0.1,
            "lcTimeToImpatience": 30.0, "lcAccelLat": 1.2}  # fmt: skip
LC_SNAKE = {"lc_strategic": 2.0, "lc_cooperative": 0.5, "lc_speed_gain": 3.0,
            "lc_keep_right": 0.0, "lc_look_ahead_left": 1.5, "lc_speed_gain_right": 0.7,
            "lc_sublane": 2.0, "lc_pushy": 0.3, "lc_pushy_gap": 0.4, "lc_assertive": 2.0,
            "lc_impatience": 0.1, "lc_time_to_impatience": 30.0, "lc_accel_lat": 1.2}  # fmt: skip


def test_camel_case_keywords_give_the_same_params_as_snake_case() -> None:
    cf = camel(SumoCarFollowingParams, accel=1.0, decel=1.5, **CF_CAMEL)
    assert cf == SumoCarFollowingParams(accel=1.0, decel=1.5, **CF_SNAKE)
    assert cf.controller_params["minGap"] == 1.0 and cf.controller_params["maxSpeed"] == 20
    lc = camel(SumoLaneChangeParams, model="SL2015", **LC_CAMEL)
    assert lc == SumoLaneChangeParams(model="SL2015", **LC_SNAKE)
    assert float(lc.controller_params["lcPushyGap"]) == 0.4


def test_a_keyword_given_both_ways_or_misspelt_is_a_type_error() -> None:
    with pytest.raises(TypeError, match="'minGap' and 'min_gap' are the same setting"):
        SumoCarFollowingParams(minGap=1, min_gap=2)  # type: ignore[call-arg]
    with pytest.raises(TypeError, match=r"'min_gapp' \(did you mean 'min_gap'\?\)"):
        SumoCarFollowingParams(min_gapp=1)  # type: ignore[call-arg]


def test_the_yaml_names_the_snake_case_key_for_a_camel_case_one(tmp_path: Path) -> None:
    path = tmp_path / "x.yaml"
    path.write_text("name: x\nvehicles:\n  - id: a\n    car_following: {minGap: 1}\n")
    with pytest.raises(ConfigError, match=r"minGap.*Flow's old spelling; write 'min_gap'"):
        load_config(path)
    path.write_text("name: x\nvehicles:\n  - id: a\n    car_following: {min_gapp: 1}\n")
    with pytest.raises(ConfigError, match=r"did you mean 'min_gap'"):
        load_config(path)


def test_missing_flow_fields_are_there_with_flows_defaults() -> None:
    sim = SumoParams()
    assert (sim.port, sim.no_step_log, sim.save_render, sim.sight_radius, sim.show_radius,
            sim.pxpm, sim.overtake_right, sim.num_clients, sim.color_by_speed,
            sim.force_color_update, sim.emission_path) == (
        None, True, False, 25, False, 2, False, 1, False, False, None)  # fmt: skip
    assert EnvParams().done_at_exit is True and math.isinf(EnvParams().horizon)
    lc = SumoLaneChangeParams()
    assert (lc.lc_look_ahead_left, lc.lc_speed_gain_right, lc.lc_sublane, lc.lc_pushy,
            lc.lc_pushy_gap, lc.lc_assertive, lc.lc_accel_lat) == (
        2.0, 1.0, 1.0, 0, 0.6, 1, 1.0)  # fmt: skip


def test_sumo_params_keep_every_flow_argument() -> None:
    sim = SumoParams(port=None, sim_step=0.125, no_step_log=False, render=True,
                     save_render=True, sight_radius=50, show_radius=True, pxpm=10,
                     overtake_right=True, seed=204, restart_instance=True,
                     print_warnings=False, teleport_time=-1)  # fmt: skip
    assert (sim.sim_step, sim.no_step_log, sim.sight_radius, sim.pxpm, sim.seed) == (
        0.125, False, 50, 10, 204)
    cfg = from_flow_params({**ring_flow_params(), "sim": sim}).config
    assert cfg.sim == sim  # through the YAML model and back, nothing lost


def test_lane_change_controller_params_depend_on_the_model() -> None:
    lc2013 = SumoLaneChangeParams().controller_params
    assert sorted(lc2013) == sorted(
        ["laneChangeModel", "lcStrategic", "lcCooperative", "lcSpeedGain", "lcKeepRight"]
    )
    sl2015 = SumoLaneChangeParams(model="SL2015").controller_params
    assert len(sl2015) == 12 and sl2015["lcLookaheadLeft"] == "2.0"


def test_an_unknown_lane_change_model_falls_back_to_lc2013_in_python_only(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.WARNING):
        lc = SumoLaneChangeParams(model="foo")
    assert lc.controller_params["laneChangeModel"] == "LC2013" and "foo" in caplog.text
    path = tmp_path / "x.yaml"
    path.write_text("name: x\nvehicles:\n  - id: a\n    lane_change: {model: SL2016}\n")
    with pytest.raises(ConfigError, match=r"did you mean 'SL2015'"):
        load_config(path)


def test_controller_params_write_through_to_the_fields() -> None:
    cf = SumoCarFollowingParams()
    cf.controller_params["minGap"] = 0.5
    assert cf.min_gap == 0.5 and cf.controller_params["minGap"] == 0.5
    lc = SumoLaneChangeParams()
    lc.controller_params["lcStrategic"] = "3.0"
    assert lc.lc_strategic == 3.0
    with pytest.raises(KeyError, match="did you mean 'minGap'"):
        cf.controller_params["mingap"] = 1


def test_vehicle_params_carry_flows_per_type_views() -> None:
    vehicles = VehicleParams()
    cf = SumoCarFollowingParams(speed_mode="obey_safe_speed", min_gap=0)
    vehicles.add("human", acceleration_controller=(IDMController, {"noise": 0.2}),
                 routing_controller=(ContinuousRouter, {}), car_following_params=cf,
                 num_vehicles=2, color="red")  # fmt: skip
    vehicles.add("rl", acceleration_controller=(RLController, {}), num_vehicles=1)
    params = vehicles.type_parameters["human"]
    assert params["acceleration_controller"] == (IDMController, {"noise": 0.2})
    assert params["routing_controller"] == (ContinuousRouter, {})
    assert params["car_following_params"] is cf and params["color"] == "red"
    assert vehicles.type_parameters["rl"]["routing_controller"] is None
    assert vehicles.minGap == {"human": 0, "rl": 2.5}
    assert vehicles.types[0]["veh_id"] == "human"
    assert vehicles.types[0]["type_params"]["minGap"] == 0
    assert vehicles.types[0]["type_params"]["laneChangeModel"] == "LC2013"
    assert vehicles.ids == ["human_0", "human_1", "rl_0"] and vehicles.num_rl_vehicles == 1


def test_vtype_attributes_are_what_the_route_file_gets() -> None:
    from flowrun.config.vtype import vtype_attributes

    attrs = vtype_attributes(SumoCarFollowingParams(min_gap=0), SumoLaneChangeParams())
    assert attrs["minGap"] == "0" and attrs["length"] == "5.0" and attrs["decel"] == "7.5"
    assert attrs["laneChangeModel"] == "LC2013" and "lcSublane" not in attrs
    assert all(isinstance(v, str) for v in attrs.values())
    sl = vtype_attributes(
        SumoCarFollowingParams(), SumoLaneChangeParams(model="SL2015", lc_impatience=0.5)
    )
    assert sl["lcSublane"] == "1.0" and sl["lcImpatience"] == "0.5"
    assert "lcTimeToImpatience" not in sl  # Flow's infinite default is SUMO's own


# -- speed and lane-change modes are SUMO's ints ---------------------------------------------


@pytest.mark.parametrize(
    ("mode", "value"),
    [
        ("aggressive", 0),
        ("obey_safe_speed", 1),
        ("no_collide", 7),
        ("right_of_way", 25),
        ("all_checks", 31),
        (9, 9),
    ],
)
def test_speed_modes_are_stored_as_flows_ints(mode: Any, value: int) -> None:
    assert SumoCarFollowingParams(speed_mode=mode).speed_mode == value


def test_a_mode_set_later_by_name_is_stored_as_its_int() -> None:
    cf = SumoCarFollowingParams()
    cf.speed_mode = "all_checks"
    assert cf.speed_mode == 31
    lc = SumoLaneChangeParams()
    lc.lane_change_mode = "sumo_default"
    assert lc.lane_change_mode == 1621


@pytest.mark.parametrize(
    ("mode", "value"),
    [
        ("no_lc_safe", 512),
        ("no_lc_aggressive", 0),
        ("sumo_default", 1621),
        ("no_strategic_aggressive", 1108),
        ("only_strategic_safe", 513),
        ("no_cooperative_safe", 1617),
        ("only_speed_gain_safe", 528),
        ("only_right_drive_safe", 576),
        (277, 277),
    ],
)
def test_lane_change_modes_are_flows_ints(mode: Any, value: int) -> None:
    assert SumoLaneChangeParams(lane_change_mode=mode).lane_change_mode == value


def test_old_lane_change_names_get_what_flows_last_release_gives_with_a_warning(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.WARNING):
        mode = SumoLaneChangeParams(lane_change_mode="strategic").lane_change_mode
    assert mode == 512 and "sumo_default" in caplog.text
    path = tmp_path / "x.yaml"
    path.write_text("name: x\nvehicles:\n  - {id: a, lane_change: {lane_change_mode: strategic}}\n")
    with pytest.raises(ConfigError, match=r"lane_change_mode.*Write 'sumo_default'"):
        load_config(path)


def test_unknown_mode_names_are_errors_with_a_suggestion() -> None:
    with pytest.raises(ConfigError, match=r"did you mean 'aggressive'"):
        SumoCarFollowingParams(speed_mode="agressive")
    with pytest.raises(ConfigError, match=r"integer >= 0"):
        SumoCarFollowingParams(speed_mode=-1)


def test_yaml_mode_names_load_as_ints_and_are_written_back_as_names(tmp_path: Path) -> None:
    from flowrun.config.dump import dump_config

    path = tmp_path / "x.yaml"
    path.write_text(
        "name: x\nnetwork: {type: ring}\n"
        "vehicles:\n  - id: a\n    car_following: {speed_mode: aggressive}\n"
        "    lane_change: {lane_change_mode: 1621}\n"
        "  - id: b\n    car_following: {speed_mode: 9}\n"
    )
    cfg = load_config(path)
    assert cfg.vehicles.groups[0].car_following_params.speed_mode == 0
    dumped = yaml.safe_load(dump_config(cfg))["vehicles"]
    assert dumped[0]["car_following"]["speed_mode"] == "aggressive"
    assert dumped[0]["lane_change"]["lane_change_mode"] == "sumo_default"
    assert dumped[1]["car_following"]["speed_mode"] == 9  # no name: the int
    again = tmp_path / "again.yaml"
    again.write_text(dump_config(cfg))
    assert load_config(again) == cfg


# -- 3. validate and train take Flow config modules ------------------------------------------


@pytest.fixture
def app() -> typer.Typer:
    from flowrun.cli import commands_config, commands_run, commands_train

    app = typer.Typer()
    commands_config.register(app)
    commands_run.register(app)
    commands_train.register(app)
    return app


def test_validate_takes_a_flow_config_module(app: typer.Typer) -> None:
    result = CliRunner().invoke(
        app, ["validate", str(EXAMPLES / "ring.py"), "--set", "sim.render=false"]
    )
    assert result.exit_code == 0, result.output
    data = yaml.safe_load(result.stdout)
    assert data["name"] == "ring" and data["env"]["class"] == "AccelEnv"
    assert data["sim"]["render"] is False and data["initial"]["bunching"] == 20


def test_train_takes_a_flow_config_module_with_default_training(
    app: typer.Typer, monkeypatch: pytest.MonkeyPatch
) -> None:
    import flowrun.training.deps
    import flowrun.training.trainer

    seen: list[Any] = []

    class Stop(Exception):
        pass

    def fake_train(cfg: Any, **kwargs: Any) -> Any:
        seen.append(cfg)
        raise Stop

    monkeypatch.setattr(flowrun.training.deps, "require", lambda name: None)
    monkeypatch.setattr(flowrun.training.trainer, "train", fake_train)
    module = str(EXAMPLES / "singleagent_ring.py")
    result = CliRunner().invoke(app, ["train", module, "--set", "train.total_timesteps=64"])
    assert isinstance(result.exception, Stop), result.output
    (cfg,) = seen
    assert cfg.env.env_class == "WaveAttenuationPOEnv" and cfg.env.warmup_steps == 750
    assert cfg.train.total_timesteps == 64 and cfg.train.algorithm == "PPO"
    seen.clear()
    result = CliRunner().invoke(app, ["train", module])
    assert isinstance(result.exception, Stop) and seen[0].train.algorithm == "PPO"
    assert "no train: section" in result.output


# -- 4. Flow's example configs ---------------------------------------------------------------


@pytest.mark.parametrize("name", NON_RL + RL)
def test_flow_example_configs_convert_to_equal_yaml(
    app: typer.Typer, name: str, tmp_path: Path
) -> None:
    module = EXAMPLES / f"{name}.py"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # Flow's departLane spellings
        result = CliRunner().invoke(app, ["convert", str(module)])
        assert result.exit_code == 0, result.output
        params = runpy.run_path(str(module))["flow_params"]
    out = tmp_path / f"{name}.yaml"
    out.write_text(result.stdout)
    assert load_config(out) == from_flow_params(params).config


@pytest.mark.sumo
@pytest.mark.parametrize("name", NON_RL)
def test_flow_example_configs_run_as_experiments(name: str) -> None:
    from flowrun.core.experiment import Experiment

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        params = runpy.run_path(str(EXAMPLES / f"{name}.py"))["flow_params"]
    params["sim"].render = False  # Flow's examples ask for sumo-gui
    info = Experiment(params).run(1, num_steps=50)
    assert len(info["returns"]) == 1 and info["mean_velocities"] > 0
