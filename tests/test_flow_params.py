"""Flow's ``flow_params`` API: the converter, ``Experiment(flow_params)``, the registry
functions, and the CLI (``flowrun baseline exp_config.py``, ``flowrun convert``)."""

from __future__ import annotations

import csv
import json
import textwrap
from pathlib import Path
from typing import Any

import gymnasium
import pytest
import typer
import yaml
from typer.testing import CliRunner

from flowrun.cli.commands_run import register
from flowrun.config.params import ControllerSpec
from flowrun.controllers import ContinuousRouter, IDMController
from flowrun.core.experiment import Experiment
from flowrun.core.params import EnvParams, InitialConfig, NetParams, SumoParams, VehicleParams
from flowrun.envs import Env
from flowrun.envs.ring.accel import ADDITIONAL_ENV_PARAMS, AccelEnv
from flowrun.errors import ConfigError
from flowrun.loading import load_config
from flowrun.loading.flow_module import load_flow_module
from flowrun.loading.flow_params import config_from_flow_params, from_flow_params
from flowrun.networks.ring import ADDITIONAL_NET_PARAMS, RingNetwork
from flowrun.utils.registry import env_constructor, make_create_env

HORIZON = 300

#: Flow's examples/exp_configs/non_rl/ring.py with flowrun imports (and a short horizon).
RING_MODULE = f'''\
"""Used as an example of ring experiment: 22 IDM cars on a ring creating shockwaves."""

from flowrun.controllers import IDMController, ContinuousRouter
from flowrun.core.params import SumoParams, EnvParams, InitialConfig, NetParams
from flowrun.core.params import VehicleParams
from flowrun.envs.ring.accel import AccelEnv, ADDITIONAL_ENV_PARAMS
from flowrun.networks.ring import RingNetwork, ADDITIONAL_NET_PARAMS


vehicles = VehicleParams()
vehicles.add(
    veh_id="idm",
    acceleration_controller=(IDMController, {{}}),
    routing_controller=(ContinuousRouter, {{}}),
    num_vehicles=22)


flow_params = dict(
    exp_tag='ring',
    env_name=AccelEnv,
    network=RingNetwork,
    simulator='traci',
    sim=SumoParams(render=False, sim_step=0.1),
    env=EnvParams(horizon={HORIZON}, additional_params=ADDITIONAL_ENV_PARAMS),
    net=NetParams(additional_params=ADDITIONAL_NET_PARAMS.copy()),
    veh=vehicles,
    initial=InitialConfig(bunching=20),
)
'''


def ring_params(**changes: Any) -> dict[str, Any]:
    vehicles = VehicleParams()
    vehicles.add(
        veh_id="idm",
        acceleration_controller=(IDMController, {}),
        routing_controller=(ContinuousRouter, {}),
        num_vehicles=22,
    )
    params: dict[str, Any] = dict(
        exp_tag="ring",
        env_name=AccelEnv,
        network=RingNetwork,
        simulator="traci",
        sim=SumoParams(render=False, sim_step=0.1),
        env=EnvParams(horizon=HORIZON, additional_params=ADDITIONAL_ENV_PARAMS),
        net=NetParams(additional_params=ADDITIONAL_NET_PARAMS.copy()),
        veh=vehicles,
        initial=InitialConfig(bunching=20),
    )
    params.update(changes)
    return params


def write_module(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / f"{name}.py"
    path.write_text(textwrap.dedent(text))
    return path


# ------------------------------------------------------------------ converter


def test_ring_flow_params_become_the_yaml_model() -> None:
    cfg = config_from_flow_params(ring_params())
    assert cfg.name == "ring"
    assert cfg.env.env_class == "AccelEnv" and cfg.env.horizon == HORIZON
    assert cfg.network.type == "ring"
    assert cfg.network.net_params.additional_params == ADDITIONAL_NET_PARAMS
    (group,) = cfg.vehicles.groups
    assert (group.veh_id, group.num_vehicles) == ("idm", 22)
    assert group.acceleration_controller == ControllerSpec("IDM")
    assert group.routing_controller == ControllerSpec("ContinuousRouter")
    assert cfg.initial.bunching == 20


def test_class_names_as_strings_give_the_same_config() -> None:
    by_class = config_from_flow_params(ring_params())
    by_name = config_from_flow_params(ring_params(env_name="AccelEnv", network="RingNetwork"))
    assert by_name == by_class


def test_initial_and_tls_may_be_left_out() -> None:
    params = ring_params()
    del params["initial"]
    assert from_flow_params(params).config.initial == InitialConfig()


@pytest.mark.parametrize(
    ("change", "path", "message"),
    [
        ({"exp_tga": "x"}, "exp_tga", "did you mean 'exp_tag'?"),
        ({"simulator": "aimsun"}, "simulator", "SUMO only"),
        ({"sim": {"sim_step": 0.1}}, "sim", "expected a SumoParams"),
        ({"network": "RingNetwrk"}, "network", "did you mean"),
        ({"env_name": 3}, "env_name", "environment class"),
    ],
)
def test_bad_flow_params_name_the_key(change: dict[str, Any], path: str, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        from_flow_params(ring_params(**change), source="exp.py")
    assert info.value.path == path
    assert info.value.location == "exp.py (flow_params)"
    assert message in info.value.message


def test_missing_keys_are_listed() -> None:
    params = ring_params()
    del params["veh"], params["net"]
    with pytest.raises(ConfigError, match="missing key"):
        from_flow_params(params)


def test_loader_checks_apply_to_flow_params() -> None:
    vehicles = VehicleParams()
    vehicles.add("idm", acceleration_controller=("IDMM", {}), num_vehicles=3)
    with pytest.raises(ConfigError) as info:
        from_flow_params(ring_params(veh=vehicles))
    assert info.value.path == "vehicles[0].acceleration_controller.type"


# ------------------------------------------------------------------ Experiment(flow_params)


def test_experiment_from_flow_params_runs_the_ring() -> None:
    exp = Experiment(ring_params())
    assert isinstance(exp.env, AccelEnv)
    info = exp.run(1)  # horizon from EnvParams
    assert len(info["returns"]) == len(info["velocities"]) == len(info["outflows"]) == 1
    assert len(info["per_step_returns"][0]) == HORIZON
    assert 0 < info["velocities"][0] < 10
    assert info["mean_velocities"] == info["velocities"][0]
    assert info["mean_returns"] == pytest.approx(sum(info["per_step_returns"][0]))
    assert info["outflows"] == [0.0]  # nobody leaves a ring
    assert info["metrics"][0].collisions == 0


def test_run_takes_rl_actions_and_custom_callables() -> None:
    seen: list[Any] = []

    def rl_actions(state: Any) -> None:
        seen.append(state)

    exp = Experiment(
        ring_params(), custom_callables={"n": lambda env: len(env.k.vehicle.get_ids())}
    )
    info = exp.run(2, 20, rl_actions=rl_actions)
    assert len(seen) == 40 and info["n"] == [22.0, 22.0]
    assert len(info["returns"]) == 2


def test_flow_positional_callables_and_rl_actions() -> None:
    exp = Experiment(ring_params(), {"t": lambda env: env.k.simulation.time})
    info = exp.run(1, lambda state: None)  # Flow's run(num_runs, rl_actions)
    assert len(info["per_step_returns"][0]) == HORIZON and info["t"][0] > 0


def test_infinite_horizon_needs_num_steps() -> None:
    exp = Experiment(ring_params(env=EnvParams(additional_params=ADDITIONAL_ENV_PARAMS)))
    with pytest.raises(ConfigError, match="horizon is infinite"):
        exp.run(1)


def test_convert_to_csv_writes_flows_emission_files(tmp_path: Path) -> None:
    data = tmp_path / "data"
    sim = SumoParams(sim_step=0.1, emission_path=str(data))
    exp = Experiment(ring_params(sim=sim))
    exp.run(2, 10, convert_to_csv=True)
    name = exp.env.network.name
    # Flow's names: <emission_path>/<network name>-<run>_emission.csv
    assert exp.csv_files == [data / f"{name}-0_emission.csv", data / f"{name}-1_emission.csv"]
    with exp.csv_files[0].open() as f:
        reader = csv.reader(f)
        header = next(reader)
        rows = [dict(zip(header, row, strict=True)) for row in reader]
    assert header == [
        "time", "id", "x", "y", "speed", "headway", "leader_id",
        "target_accel_with_noise_with_failsafe", "target_accel_no_noise_no_failsafe",
        "target_accel_with_noise_no_failsafe", "target_accel_no_noise_with_failsafe",
        "realized_accel", "road_grade", "edge_id", "lane_number", "distance",
        "relative_position", "follower_id", "leader_rel_speed",
    ]  # fmt: skip
    assert len(rows) == 22 * 11  # the state at reset and after each of the 10 steps
    # grouped by vehicle, then time from 0 at reset in steps of sim_step (Flow's order)
    first = rows[:11]
    assert {r["id"] for r in first} == {"idm_0"}
    assert [float(r["time"]) for r in first] == [round(0.1 * k, 2) for k in range(11)]
    last = rows[-1]
    speed, lead = float(last["speed"]), last["leader_id"]
    at = [r for r in rows if r["id"] == lead and r["time"] == last["time"]]
    lead_speed = float(at[0]["speed"])
    assert float(last["leader_rel_speed"]) == pytest.approx(lead_speed - speed)
    assert float(last["target_accel_no_noise_no_failsafe"]) == pytest.approx(
        float(last["target_accel_with_noise_with_failsafe"])
    )
    assert at[0]["follower_id"] == last["id"]


def test_convert_to_csv_needs_an_emission_path() -> None:
    with pytest.raises(ConfigError, match="emission_path"):
        Experiment(ring_params()).run(1, 5, convert_to_csv=True)


# ------------------------------------------------------------------ flowrun.utils.registry


def test_make_create_env_registers_a_fresh_name() -> None:
    create_env, name = make_create_env(ring_params())
    _, again = make_create_env(ring_params())
    assert name.startswith("AccelEnv-v") and again != name
    assert name in gymnasium.registry
    env = create_env()
    assert isinstance(env, AccelEnv) and env.env_params.horizon == HORIZON
    env.close()


def test_env_constructor_evaluate_and_render() -> None:
    env = env_constructor(ring_params(), evaluate=True)()
    assert env.env_params.evaluate
    env.close()


# ------------------------------------------------------------------ config modules and CLI


@pytest.fixture
def app() -> typer.Typer:
    app = typer.Typer()
    register(app)
    return app


def test_convert_output_loads_back_equal(app: typer.Typer, tmp_path: Path) -> None:
    module = write_module(tmp_path, "ring_convert_exp", RING_MODULE)
    result = CliRunner().invoke(app, ["convert", str(module)])
    assert result.exit_code == 0, result.output
    out = tmp_path / "ring.yaml"
    out.write_text(result.stdout)
    assert yaml.safe_load(result.stdout)["env"]["class"] == "AccelEnv"
    assert load_config(out) == load_flow_module(module).config


def test_convert_out_writes_a_new_file(app: typer.Typer, tmp_path: Path) -> None:
    module = write_module(tmp_path, "ring_convert_out", RING_MODULE)
    out = tmp_path / "sub" / "ring.yaml"
    assert CliRunner().invoke(app, ["convert", str(module), "--out", str(out)]).exit_code == 0
    assert load_config(out) == load_flow_module(module).config
    again = CliRunner().invoke(app, ["convert", str(module), "--out", str(out)])
    assert again.exit_code == 1 and "exists already" in again.output


def test_baseline_runs_a_flow_config_module(app: typer.Typer, tmp_path: Path) -> None:
    module = write_module(tmp_path, "ring_baseline_exp", RING_MODULE)
    out = tmp_path / "runs"
    result = CliRunner().invoke(app, ["baseline", str(module), "--out", str(out), "--steps", "50"])
    assert result.exit_code == 0, result.output
    (run_dir,) = (out / "ring").iterdir()
    assert (run_dir / "run_0.mcap").is_file() and (run_dir / "metrics.json").is_file()
    saved = load_config(run_dir / "config.yaml")
    assert saved.env.env_class == "AccelEnv" and saved.vehicles.num_vehicles == 22
    assert "ring: 1 run(s) x 50 steps" in result.output


USER_ENV_MODULE = RING_MODULE.replace("env_name=AccelEnv,", "env_name=SlowAccelEnv,").replace(
    "vehicles = VehicleParams()",
    '''class SlowAccelEnv(AccelEnv):
    """A user's env defined in the config module."""

    def compute_reward(self, rl_actions, **kwargs):
        return -1.0


vehicles = VehicleParams()''',
)


def test_a_user_env_class_in_the_module_is_the_one_that_runs(
    app: typer.Typer, tmp_path: Path
) -> None:
    module = write_module(tmp_path, "user_env_exp", USER_ENV_MODULE)
    flow = load_flow_module(module)
    assert flow.config.env.env_class == "user_env_exp:SlowAccelEnv"
    assert flow.env_class is not None and flow.env_class.__name__ == "SlowAccelEnv"
    out = tmp_path / "runs"
    result = CliRunner().invoke(app, ["baseline", str(module), "--out", str(out), "--steps", "5"])
    assert result.exit_code == 0, result.output
    (run_dir,) = (out / "ring").iterdir()
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["runs"][0]["episode_return"] == -5.0  # five steps of the module's reward
    converted = CliRunner().invoke(app, ["convert", str(module)])
    yaml_file = tmp_path / "user.yaml"
    yaml_file.write_text(converted.stdout)
    assert load_config(yaml_file) == flow.config


@pytest.mark.parametrize(
    ("text", "message", "line"),
    [
        ("x = 1\n", "defines no 'flow_params'", None),
        ("import os\n\nraise RuntimeError('boom')\n", "RuntimeError: boom", 3),
        ("def f(:\n", "SyntaxError", 1),
        ("flow_params = 3\n", "expected a dict", None),
    ],
)
def test_bad_modules_give_one_error_and_exit_1(
    app: typer.Typer, tmp_path: Path, text: str, message: str, line: int | None
) -> None:
    module = write_module(tmp_path, "bad_exp", text)
    for command in ("baseline", "convert"):
        result = CliRunner().invoke(
            app,
            [command, str(module), "--out", str(tmp_path / "o")]
            if command == "baseline"
            else [command, str(module)],
        )
        assert result.exit_code == 1
        assert message in result.output and "Traceback" not in result.output
        if line is not None:
            assert f"{module.resolve()}:{line}" in result.output


def test_missing_module_file(app: typer.Typer, tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["convert", str(tmp_path / "nope.py")])
    assert result.exit_code == 1 and "not found" in result.output


def test_env_is_a_gymnasium_env() -> None:
    create_env, _ = make_create_env(ring_params())
    env = create_env()
    assert isinstance(env, Env) and isinstance(env, gymnasium.Env)
    env.close()
