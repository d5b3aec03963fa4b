"""``--set key.path=value`` overrides: YAML values, list indices, located errors."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from flowrun.config import ControllerSpec
from flowrun.config.overrides import parse_key
from flowrun.errors import ConfigError
from flowrun.loading import load_config

BASE = """\
name: base
sim: {step: 0.1}
network: {type: ring, length: 230}
vehicles:
  - id: idm
    count: 20
    acceleration_controller: IDM
  - id: rl
    count: 1
    acceleration_controller: {type: RLController}
"""


@pytest.fixture
def base(tmp_path: Path) -> Path:
    path = tmp_path / "base.yaml"
    path.write_text(BASE)
    return path


def test_parse_key_accepts_dots_and_brackets() -> None:
    assert parse_key("vehicles.0.count") == ("vehicles", 0, "count")
    assert parse_key("vehicles[1].acceleration_controller.v0") == (
        "vehicles",
        1,
        "acceleration_controller",
        "v0",
    )


def test_scalar_overrides_are_read_as_yaml(base: Path) -> None:
    cfg = load_config(base, ["sim.step=0.5", "env.horizon=.inf", "sim.render=false", "sim.seed=7"])
    assert cfg.sim.sim_step == 0.5 and cfg.sim.seed == 7 and cfg.sim.render is False
    assert math.isinf(cfg.env.horizon)


@pytest.mark.parametrize("key", ["vehicles.0.count", "vehicles[0].count"])
def test_list_items_by_index(base: Path, key: str) -> None:
    cfg = load_config(base, [f"{key}=10"])
    assert [g.num_vehicles for g in cfg.vehicles.groups] == [10, 1]


def test_controller_parameter_on_a_bare_controller_name(base: Path) -> None:
    cfg = load_config(base, ["vehicles[0].acceleration_controller.v0=25"])
    assert cfg.vehicles.groups[0].acceleration_controller == ControllerSpec("IDM", {"v0": 25})


def test_override_into_network_and_missing_sections(base: Path) -> None:
    cfg = load_config(base, ["network.length=260", "train.n_envs=4", "env.additional_params.k=1"])
    assert cfg.network.net_params.additional_params["length"] == 260
    assert cfg.train is not None and cfg.train.n_envs == 4
    assert cfg.env.additional_params == {"k": 1}


def test_later_override_wins_and_values_are_never_evaluated(base: Path) -> None:
    cfg = load_config(base, ["name=first", "name=__import__('os').getcwd()"])
    assert cfg.name == "__import__('os').getcwd()"


def test_flow_collection_value(base: Path) -> None:
    cfg = load_config(base, ["train.policy_kwargs={net_arch: [64, 64]}"])
    assert cfg.train is not None and cfg.train.policy_kwargs == {"net_arch": [64, 64]}


@pytest.mark.parametrize(
    ("override", "path", "message"),
    [
        ("sim.stpe=0.2", "sim.stpe", "did you mean 'step'?"),
        ("vehicles.0.cuont=3", "vehicles[0].cuont", "did you mean 'count'?"),
        ("vehicles[0].count=many", "vehicles[0].count", "expected an integer, got 'many'"),
        ("sim.step=-1", "sim.step", "must be greater than 0, got -1"),
        ("vehicles.5.count=1", "vehicles[5]", "index 5 is out of range: 'vehicles' has 2"),
        ("sim.step.x=1", "sim.step", "is a value"),
        ("sim.step", "", "must look like key.path=value"),
    ],
)
def test_bad_override_is_an_error_located_at_set(
    base: Path, override: str, path: str, message: str
) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(base, [override])
    assert info.value.location == "--set"
    if path:
        assert info.value.path == path
    assert message in info.value.message


def test_error_at_a_key_not_overridden_keeps_its_file_line(base: Path) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(base, ["vehicles.0.count=60"])  # 61 cars do not fit on 230 m
    assert (info.value.location, info.value.path) == (f"{base}:3", "network.length")


def test_override_of_a_controller_name_is_located_at_set(base: Path) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(base, ["vehicles.1.acceleration_controller.type=RLControler"])
    assert info.value.location == "--set"
    assert info.value.path == "vehicles[1].acceleration_controller.type"
    assert "did you mean 'RLController'?" in info.value.message
