"""Checks that span sections: controller names and parameters, network limits.

These call the controller and network registries; their errors come back with the config's
key path and ``file:line``.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from flowrun.errors import ConfigError
from flowrun.loading import load_config


def load_error(tmp_path: Path, text: str) -> tuple[ConfigError, str]:
    path = tmp_path / "exp.yaml"
    path.write_text(textwrap.dedent(text))
    with pytest.raises(ConfigError) as info:
        load_config(path)
    return info.value, str(path)


def test_unknown_controller_name_points_at_its_type_key(tmp_path: Path) -> None:
    err, file = load_error(
        tmp_path,
        """\
        name: x
        vehicles:
          - id: a
            acceleration_controller:
              v0: 30
              type: IDN
        """,
    )
    assert (err.location, err.path) == (f"{file}:6", "vehicles[0].acceleration_controller.type")
    assert "did you mean 'IDM'?" in err.message


def test_unknown_bare_controller_name_points_at_the_controller_key(tmp_path: Path) -> None:
    err, file = load_error(
        tmp_path, "name: x\nvehicles:\n  - id: a\n    routing_controller: ContinuousRuoter\n"
    )
    assert (err.location, err.path) == (f"{file}:4", "vehicles[0].routing_controller")
    assert "did you mean 'ContinuousRouter'?" in err.message


def test_unknown_controller_parameter_points_at_the_parameter(tmp_path: Path) -> None:
    err, file = load_error(
        tmp_path,
        """\
        name: x
        vehicles:
          - id: a
            acceleration_controller:
              type: IDM
              v0: 30
              v00: 20
        """,
    )
    assert (err.location, err.path) == (f"{file}:7", "vehicles[0].acceleration_controller.v00")
    assert "did you mean 'v0'?" in err.message


def test_bad_controller_parameter_value_points_at_the_parameter(tmp_path: Path) -> None:
    err, file = load_error(
        tmp_path,
        """\
        name: x
        vehicles:
          - id: a
            acceleration_controller:
              type: IDM
              a: 1
              v0: -30
        """,
    )
    assert (err.location, err.path) == (f"{file}:7", "vehicles[0].acceleration_controller.v0")
    assert "v0" in err.message


def test_controller_of_the_wrong_kind_is_refused(tmp_path: Path) -> None:
    err, file = load_error(
        tmp_path, "name: x\nvehicles:\n  - id: a\n    routing_controller: {type: IDM}\n"
    )
    assert (err.location, err.path) == (f"{file}:4", "vehicles[0].routing_controller.type")
    assert "routing" in err.message


def test_unknown_network_type(tmp_path: Path) -> None:
    err, file = load_error(tmp_path, "name: x\nnetwork:\n  length: 230\n  type: rign\n")
    assert (err.location, err.path) == (f"{file}:4", "network.type")
    assert "did you mean 'ring'?" in err.message


def test_more_cars_than_fit_on_the_ring(tmp_path: Path) -> None:
    err, file = load_error(
        tmp_path,
        """\
        name: x
        network:
          type: ring
          length: 100
        vehicles:
          - {id: a, count: 22}
        """,
    )
    assert (err.location, err.path) == (f"{file}:4", "network.length")
    assert "22 vehicles" in err.message


def test_env_class_is_not_imported_at_load_time(tmp_path: Path) -> None:
    path = tmp_path / "exp.yaml"
    path.write_text("name: x\nnetwork: {type: ring}\nenv: {class: 'my_envs:MyEnv'}\n")
    assert load_config(path).env.env_class == "my_envs:MyEnv"
