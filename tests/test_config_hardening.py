"""Inputs an adversarial user writes (issues 10 and 16): each refused as one located
ConfigError, or working as a Flow user expects. One test per defect found."""

from __future__ import annotations

import logging
import math
import os
from pathlib import Path

import numpy as np
import pytest

from flowrun.config.yamlio import load_scalar
from flowrun.errors import ConfigError
from flowrun.loading import load_config
from flowrun.preflight.checks import validate_config

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
SUGIYAMA = CONFIGS / "sugiyama.yaml"
RING_WAVE = CONFIGS / "ring_wave.yaml"


def mutated(tmp_path: Path, base: Path, old: str, new: str) -> Path:
    """``base`` with its first ``old`` replaced by ``new``, written to ``tmp_path``."""
    text = base.read_text()
    assert old in text, old
    path = tmp_path / base.name
    path.write_text(text.replace(old, new, 1))
    return path


def refusal(path: Path, *overrides: str) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        validate_config(path, overrides)
    err = info.value
    assert "\n" not in str(err)
    return err


def line_of(path: Path, needle: str) -> int:
    return next(i for i, ln in enumerate(path.read_text().splitlines(), 1) if needle in ln)


@pytest.mark.parametrize(
    ("old", "new", "key", "expected"),
    [
        ("step: 0.1", "step: 1:30", "sim.step", "expected a number, got '1:30'"),
        ("horizon: 3000", "horizon: 0.5", "env.horizon", "whole number of steps"),
        ("length: 230", "length: .inf", "network.length", "finite"),
        ("length: 230", "length: 1e308", "network.length", "at most 1e+06"),
        ("perturbation: 0", "perturbation: .nan", "initial.perturbation", ".nan"),
        ("perturbation: 0", "perturbation: .inf", "initial.perturbation", "finite"),
        ("perturbation: 0", "perturbation: 0\n  x0: 1e308", "initial.x0", "between"),
        ("max_accel: 1", "max_accel: .nan", "env.additional_params.max_accel", "finite"),
        ("max_accel: 1", "max_accel: [1]", "env.additional_params.max_accel", "> 0"),
        ("max_accel: 1", "max_accel: fast", "env.additional_params.max_accel", "> 0"),
        ("max_accel: 1", "max_accel: 1e308", "env.additional_params.max_accel", "finite"),
        ("step: 0.1", "step: 10", "sim.step", "shortest edge"),
        ("seed: 0", "seed: 0\n  teleport_time: .nan", "sim.teleport_time", "-1"),
        ("id: idm", "id: 'a b'", "vehicles[0].id", "SUMO refuses"),
        ("count: 22", "count: 22\n    color: notacolor", "vehicles[0].color", "colour"),
        ("count: 22", "count: 22\n    initial_speed: 31", "vehicles[0].initial_speed", "31"),
        ("count: 22", "count: 22\n    car_following: {impatience: 5}",
         "vehicles[0].car_following.impatience", "between 0 and 1"),
        ("v0: 30", "v0: 1e308", "vehicles[0].acceleration_controller.v0", "finite"),
        ("perturbation: 0", "perturbation: 0\n  min_gap: 50", "initial.min_gap", "min_gap"),
        ("type: ring", "type: ring\n  template: x.net.xml", "network.template", "ignored"),
        ("count: 22", "count: 100000000000", "vehicles[0].count", "at most 100000"),
        ("env:", "env:\n  additional_params: {max_accel: 1}\n  foo: 1\nx:", "env.foo", "unknown"),
    ],
)
def test_impossible_values_are_refused_at_their_line(
    tmp_path: Path, old: str, new: str, key: str, expected: str
) -> None:
    path = mutated(tmp_path, SUGIYAMA, old, new)
    err = refusal(path)
    assert err.path == key
    assert err.location == f"{path}:{line_of(path, key.split('.')[-1].split('[')[0] + ':')}"
    assert expected in err.message


@pytest.mark.parametrize(
    ("old", "new", "key", "expected"),
    [
        ("batch_size: 1000", "batch_size: 0", "train.hyperparams.batch_size", ">= 1"),
        ("n_steps: 3000", "n_steps: -1", "train.hyperparams.n_steps", ">= 1"),
        ("gamma: 0.999", "gamma: 2", "train.hyperparams.gamma", "<= 1"),
        ("gamma: 0.999", "gamma: .nan", "train.hyperparams.gamma", "finite"),
        ("learning_rate: 3.0e-4", "learning_rate: {linear: [.nan, 0]}",
         "train.hyperparams.learning_rate.linear[0]", "finite"),
        ("count: 1\n", "count: 0\n", "env.class", "RLController"),
    ],
)
def test_training_settings_are_refused_before_any_run(
    tmp_path: Path, old: str, new: str, key: str, expected: str
) -> None:
    path = mutated(tmp_path, RING_WAVE, old, new)
    err = refusal(path)
    assert (err.path, expected in err.message) == (key, True), str(err)
    assert err.location.startswith(f"{path}:")


def test_the_same_checks_run_in_load_config_for_baseline_and_train(tmp_path: Path) -> None:
    for old, new in [("gamma: 0.999", "gamma: 2"), ("step: 0.1", "step: 10")]:
        with pytest.raises(ConfigError):
            load_config(mutated(tmp_path, RING_WAVE, old, new))


def test_yaml_1_2_numbers() -> None:
    assert load_scalar("1:30") == "1:30"
    assert load_scalar("1e-3") == 0.001
    assert load_scalar("1.5e3") == 1500.0
    assert load_scalar("2024-05-01") == "2024-05-01"
    assert load_scalar(".inf") == math.inf and load_scalar("yes") is True


def test_an_override_is_read_like_the_file(tmp_path: Path) -> None:
    err = refusal(SUGIYAMA, "sim.step=1:30")
    assert (err.path, err.location) == ("sim.step", "--set")
    assert load_config(SUGIYAMA, ["sim.step=5e-2"]).sim.sim_step == 0.05


@pytest.mark.parametrize(
    ("content", "line", "expected"),
    [
        (b"name: x\nsim:\n  step: 0.1\x00\n", 3, "NUL byte"),
        (b"name: x\nsim: {}\nnetwork: {type: r\xe9ng}\n", 3, "not UTF-8"),
        (b"name: x\n\x07bell: 1\n", 2, "#x0007"),
    ],
)
def test_binary_content_is_one_error_naming_file_and_line(
    tmp_path: Path, content: bytes, line: int, expected: str
) -> None:
    path = tmp_path / "bad.yaml"
    path.write_bytes(content)
    err = refusal(path)
    assert err.location == f"{path}:{line}" and expected in err.message


def test_alias_bomb_and_deep_nesting_are_refused_cheaply(tmp_path: Path) -> None:
    rows = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    rows += [f"a{n}: &a{n} [{', '.join([f'*a{n - 1}'] * 10)}]" for n in range(1, 9)]
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text("\n".join(rows) + "\n")
    err = refusal(bomb)
    assert "100000 values" in err.message and err.location.startswith(f"{bomb}:")
    deep = tmp_path / "deep.yaml"
    deep.write_text("name: x\nsim: " + "[" * 5000 + "]" * 5000 + "\n")
    err = refusal(deep)
    assert "nested" in err.message and err.location == f"{deep}:2"


def test_not_a_regular_file_is_refused_without_reading(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe.yaml"
    os.mkfifo(fifo)  # reading it would block forever
    assert "not a regular file" in refusal(fifo).message
    assert "directory" in refusal(tmp_path).message
    big = tmp_path / "big.yaml"
    big.write_bytes(b"# " + b"x" * (2 << 20) + b"\n")
    assert "bytes" in refusal(big).message


def test_ignored_settings_are_warned(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    path = mutated(tmp_path, SUGIYAMA, "seed: 0", "seed: 0\n  emission_path: /tmp/x")
    with caplog.at_level(logging.WARNING):
        validate_config(path)
    assert f"{path}:8: sim.emission_path is used only by Experiment.run" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        validate_config(SUGIYAMA, ["sim.port=9000", "sim.save_render=true"])
        assert "sim.port is Flow's TraCI port" in caplog.text
        assert "sim.save_render is for Flow's pyglet renderer" in caplog.text
        caplog.clear()
        validate_config(SUGIYAMA)  # the stock config: no warnings
    assert caplog.text == ""


def test_settings_flow_accepts_still_load(tmp_path: Path) -> None:
    overrides = ["initial.spacing=random", "vehicles[0].color=1,0,0", "initial.min_gap=0.5"]
    cfg = load_config(SUGIYAMA, [*overrides, "vehicles[0].initial_speed=30"])
    assert (cfg.initial.min_gap, cfg.vehicles.groups[0].color) == (0.5, "1,0,0")


@pytest.mark.sumo
def test_random_spacing_inserts_every_car_of_the_stock_ring() -> None:
    """It failed for every seed: the random gaps ignored the vehicle type's minGap."""
    from flowrun.envs.factory import make_env

    cfg = load_config(SUGIYAMA, ["initial.spacing=random"])
    starts = []
    env = make_env(cfg)
    try:
        for seed in (0, 1, 2):
            env.reset(seed=seed)
            ids = env.k.vehicle.get_ids()
            assert len(ids) == 22
            starts.append(sorted(env.k.vehicle.get_x_by_id(v) for v in ids))
    finally:
        env.close()
    assert starts[0] != starts[1] != starts[2]
    gaps = np.diff(starts[0] + [starts[0][0] + 230.0])
    assert gaps.min() >= 5.0 + 2.5 - 1e-9  # length + SUMO's minGap, front to front


def test_sub_millisecond_steps_and_sublane_without_sl2015_are_refused(tmp_path: Path) -> None:
    assert "milliseconds" in refusal(SUGIYAMA, "sim.step=0.0015").message
    err = refusal(SUGIYAMA, "sim.lateral_resolution=0.5")
    assert err.path == "sim.lateral_resolution" and "SL2015" in err.message
    ok = ["sim.lateral_resolution=0.5", "vehicles[0].lane_change.model=SL2015"]
    assert load_config(SUGIYAMA, ok).sim.lateral_resolution == 0.5
