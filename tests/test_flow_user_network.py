"""A user's own ``Network`` subclass (Flow's ``specify_*`` hooks, no template) given as
``flow_params["network"]`` builds exactly the road its hooks describe and runs through
``Experiment(flow_params)``, ``flowrun baseline my_config.py``, ``gymnasium.make``, a YAML
config naming it by import path, and training (real SUMO)."""

from __future__ import annotations

import json
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.core.experiment import Experiment
from flowrun.envs.factory import make_env, make_network
from flowrun.errors import ConfigError
from flowrun.loading.flow_module import load_flow_module
from flowrun.loading.loader import load_config
from flowrun.networks.registry import network_class
from flowrun.utils.registry import make_create_env

#: A rectangle loop written as Flow teaches: the south side is a two-lane edge of type
#: ``wide`` (20 m/s) merging into the one-lane ``narrow`` east side, both of its lanes
#: connected to that one lane; edge starts leave 10 m between edges (Flow's junction room).
MODULE = '''\
from flowrun.controllers import IDMController, ContinuousRouter, RLController
from flowrun.core.params import SumoParams, EnvParams, NetParams, InitialConfig
from flowrun.core.params import VehicleParams, SumoCarFollowingParams
from flowrun.envs.ring.accel import AccelEnv, ADDITIONAL_ENV_PARAMS
from flowrun.networks import Network

ADDITIONAL_NET_PARAMS = {"width": 120, "height": 80}


class Rectangle(Network):
    def specify_nodes(self, net_params):
        w = net_params.additional_params["width"]
        h = net_params.additional_params["height"]
        return [{"id": "sw", "x": 0, "y": 0}, {"id": "se", "x": w, "y": 0},
                {"id": "ne", "x": w, "y": h}, {"id": "nw", "x": 0, "y": h}]

    def specify_types(self, net_params):
        return [{"id": "wide", "numLanes": 2, "speed": 20},
                {"id": "narrow", "numLanes": 1, "speed": 15}]

    def specify_edges(self, net_params):
        w = net_params.additional_params["width"]
        h = net_params.additional_params["height"]
        return [{"id": "south", "from": "sw", "to": "se", "length": w, "type": "wide"},
                {"id": "east", "from": "se", "to": "ne", "length": h, "type": "narrow"},
                {"id": "north", "from": "ne", "to": "nw", "length": w, "type": "narrow"},
                {"id": "west", "from": "nw", "to": "sw", "length": h, "numLanes": 1,
                 "speed": 25}]

    def specify_connections(self, net_params):
        return {"se": [{"from": "south", "to": "east", "fromLane": 0, "toLane": 0},
                       {"from": "south", "to": "east", "fromLane": 1, "toLane": 0}],
                "sw": [{"from": "west", "to": "south", "fromLane": 0, "toLane": 0},
                       {"from": "west", "to": "south", "fromLane": 0, "toLane": 1}]}

    def specify_routes(self, net_params):
        loop = ["south", "east", "north", "west"]
        return {e: loop[i:] + loop[:i] for i, e in enumerate(loop)}

    def specify_edge_starts(self):
        w = self.net_params.additional_params["width"]
        h = self.net_params.additional_params["height"]
        return [("south", 0), ("east", w + 10), ("north", w + h + 20),
                ("west", 2 * w + h + 30)]


vehicles = VehicleParams()
vehicles.add(veh_id="human", acceleration_controller=(IDMController, {}),
             routing_controller=(ContinuousRouter, {}), num_vehicles=9,
             car_following_params=SumoCarFollowingParams(speed_mode="right_of_way"))
vehicles.add(veh_id="rl", acceleration_controller=(RLController, {}),
             routing_controller=(ContinuousRouter, {}), num_vehicles=1,
             car_following_params=SumoCarFollowingParams(speed_mode="right_of_way"))

flow_params = dict(
    exp_tag="rectangle",
    env_name=AccelEnv,
    network=Rectangle,
    simulator="traci",
    sim=SumoParams(sim_step=0.1, render=False, seed=3),
    env=EnvParams(horizon=200, additional_params=ADDITIONAL_ENV_PARAMS),
    net=NetParams(additional_params=ADDITIONAL_NET_PARAMS),
    veh=vehicles,
    initial=InitialConfig(spacing="uniform"),
)
'''

W, H = 120.0, 80.0


@pytest.fixture
def module(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The config module, written as ``my_rect_config.py`` and forgotten afterwards."""
    monkeypatch.setattr(sys, "path", list(sys.path))
    path = tmp_path / "my_rect_config.py"
    path.write_text(MODULE)
    yield path
    sys.modules.pop("my_rect_config", None)


def flow_params(module: Path) -> dict[str, Any]:
    load_flow_module(module)  # imports it as ``my_rect_config``
    params: dict[str, Any] = sys.modules["my_rect_config"].flow_params
    return params


def test_the_class_is_named_by_import_path_and_builds_its_hooks_road(module: Path) -> None:
    flow = load_flow_module(module)
    assert flow.config.network.type == "my_rect_config:Rectangle"
    assert flow.network_class is sys.modules["my_rect_config"].Rectangle
    spec = make_network(flow.config).spec
    lanes = {e.id: (e.lanes, e.speed, e.length) for e in spec.edges}
    assert lanes == {"south": (2, 20.0, W), "east": (1, 15.0, H), "north": (1, 15.0, W),
                     "west": (1, 25.0, H)}  # fmt: skip
    assert spec.edge_starts == {"south": 0.0, "east": W + 10, "north": W + H + 20,
                                "west": 2 * W + H + 30}  # fmt: skip
    assert spec.routes["north"] == ("north", "west", "south", "east")
    assert {(c.from_edge, c.to_edge, c.from_lane, c.to_lane) for c in spec.connections} == {
        ("south", "east", 0, 0), ("south", "east", 1, 0),
        ("west", "south", 0, 0), ("west", "south", 0, 1),
    }  # fmt: skip


@pytest.mark.sumo
def test_sumo_drives_exactly_that_road(module: Path) -> None:
    env = make_env(load_flow_module(module).config)
    try:
        env.reset(seed=0)
        api = env.k.vehicle.api
        assert api.lane.getLength("south_1") == pytest.approx(W, abs=0.01)
        assert api.lane.getMaxSpeed("east_0") == pytest.approx(15.0)
        assert api.edge.getLaneNumber("south") == 2 and api.edge.getLaneNumber("north") == 1
        to_east = {lane: [link[0] for link in api.lane.getLinks(f"south_{lane}")]
                   for lane in (0, 1)}  # fmt: skip
        assert to_east == {0: ["east_0"], 1: ["east_0"]}
        seen: set[str] = set()
        for _ in range(190):
            env.step(np.zeros(1))
            for vid in env.k.vehicle.get_ids():
                edge = env.k.vehicle.get_edge(vid)
                if edge == "north":  # Flow's absolute position: edge start + lane position
                    x = env.k.vehicle.get_x_by_id(vid)
                    assert x == pytest.approx(W + H + 20 + env.k.vehicle.get_position(vid))
                seen.add(edge)
        assert {"south", "east", "north", "west"} <= seen  # round the loop, not stuck
    finally:
        env.close()


@pytest.mark.sumo
def test_experiment_runs_the_flow_params(module: Path) -> None:
    info = Experiment(flow_params(module)).run(1)
    assert 0.5 < info["velocities"][0] < 20.0  # cars drive, under the road's limits
    assert len(info["returns"]) == 1


@pytest.mark.sumo
def test_baseline_cli_runs_the_config_module(module: Path, tmp_path: Path) -> None:
    out = tmp_path / "runs"
    result = CliRunner().invoke(app, ["baseline", str(module), "--out", str(out), "--steps", "40"])
    assert result.exit_code == 0, result.output
    (run_dir,) = (out / "rectangle").iterdir()
    assert load_config(run_dir / "config.yaml").network.type == "my_rect_config:Rectangle"
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["runs"][0]["collisions"] == 0


@pytest.mark.sumo
def test_gymnasium_make_of_the_registered_flow_params(module: Path) -> None:
    _, name = make_create_env(flow_params(module))
    env = gymnasium.make(name)
    try:
        obs, _ = env.reset(seed=1)
        assert obs.shape == (20,)  # AccelEnv: speed and position of the 10 cars
        obs, reward, terminated, truncated, _ = env.step(np.array([0.5]))
        assert np.isfinite(reward) and not terminated and not truncated
    finally:
        env.close()


@pytest.mark.sumo
def test_a_yaml_config_names_the_class_next_to_it(module: Path, tmp_path: Path) -> None:
    yaml_file = tmp_path / "rect.yaml"
    yaml_file.write_text(textwrap.dedent("""\
        name: rect
        env: {class: AccelEnv, horizon: 50,
              additional_params: {max_accel: 1, max_decel: 1, target_velocity: 10,
                                  sort_vehicles: false}}
        network: {type: "my_rect_config:Rectangle", width: 150, height: 80}
        vehicles:
          - {id: idm, count: 6, acceleration_controller: {type: IDM},
             routing_controller: {type: ContinuousRouter}}
        """))  # fmt: skip
    cfg = load_config(yaml_file)
    network = make_network(cfg)
    assert type(network).__name__ == "Rectangle"
    assert {e.id: e.length for e in network.spec.edges}["north"] == 150.0


def test_a_bad_import_path_or_class_is_one_clear_error(module: Path, tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"no class 'Rectangel'.*did you mean 'Rectangle'"):
        network_class("my_rect_config:Rectangel", tmp_path)
    with pytest.raises(ConfigError, match=r"is not a subclass of flowrun\.networks\.Network"):
        network_class("my_rect_config:VehicleParams", tmp_path)
    with pytest.raises(ConfigError, match="cannot import module 'no_such_mod' for network"):
        network_class("no_such_mod:Rectangle", tmp_path)


@pytest.mark.sumo
@pytest.mark.train
def test_train_learns_on_the_users_network(module: Path, tmp_path: Path) -> None:
    out = tmp_path / "runs"
    sets = ["train.total_timesteps=128", "train.hyperparams.n_steps=64",
            "train.hyperparams.batch_size=64", "env.horizon=64"]  # fmt: skip
    args = ["train", str(module), "--out", str(out)]
    for s in sets:
        args += ["--set", s]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    (run_dir,) = (out / "rectangle").iterdir()
    assert (run_dir / "final_model.zip").is_file()
    assert json.loads((run_dir / "status.json").read_text())["status"] == "complete"
