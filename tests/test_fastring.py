"""The numpy ring backend on its own: refusals, seeding, batching, episode ends, vector envs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flowrun.errors import ConfigError
from flowrun.fastring.plan import check_numpy_backend, ring_plan
from flowrun.fastring.rings import FastRings
from flowrun.fastring.vec_env import RingEpisodes, RingVecEnv, RingVectorEnv
from flowrun.training.vecenv import make_vec_env
from tests.conftest import load

NUMPY = "sim.backend=numpy"
ACCEL = ["env.class=AccelEnv", "env.additional_params.target_velocity=10",
         "env.additional_params.sort_vehicles=false"]  # fmt: skip


def wave(*overrides: str) -> object:
    return load("ring_wave", NUMPY, *overrides)


@pytest.mark.parametrize(
    ("name", "overrides", "words"),
    [
        ("ring_wave", ["network.lanes=2"], "single-lane"),
        ("figure_eight", [], "ring networks only"),
        ("ring_wave", ["env.class=TestEnv"], "env classes"),
        ("ring_wave", ["vehicles[0].acceleration_controller.fail_safe=safe_velocity"],
         "without fail-safes"),
        ("ring_wave", ["vehicles[1].car_following.speed_mode=all_checks"], "speed modes"),
        ("ring_wave", ["env.sims_per_step=2"], "one simulation step"),
        ("ring_wave", ["vehicles[1].car_following.car_follow_model=Krauss"], "SUMO's IDM"),
        ("ring_wave", [*ACCEL, "env.additional_params.sort_vehicles=true"], "sort"),
        ("ring_wave", [*ACCEL, "env.additional_params.relative_positions=true"],
         "absolute positions only"),
    ],
)  # fmt: skip
def test_a_config_the_backend_cannot_run_is_refused_with_one_config_error(
    name: str, overrides: list[str], words: str
) -> None:
    cfg = load(name, NUMPY, *overrides)
    with pytest.raises(ConfigError, match=words) as err:
        check_numpy_backend(cfg)
    assert "use sim.backend: sumo" in str(err.value)
    with pytest.raises(ConfigError, match=words):  # before any env is built
        make_vec_env(cfg, 2, 0)


def test_the_sumo_backend_is_not_checked() -> None:
    assert check_numpy_backend(load("figure_eight")) is None  # SUMO runs it
    with pytest.raises(ConfigError, match=r"use sim\.backend: sumo"):  # numpy cannot
        check_numpy_backend(load("figure_eight", "sim.backend=numpy"))


def test_same_seed_gives_the_same_episode_and_another_seed_another() -> None:
    def run(seed: int) -> np.ndarray:
        episodes = RingEpisodes(ring_plan(wave()), 3)
        obs = [episodes.reset_all([seed, seed + 1, seed + 2])]
        for _ in range(200):
            obs.append(episodes.step(np.full((3, 1), 0.3))[0])
        return np.array(obs)

    first, again, other = run(5), run(5), run(6)
    assert np.array_equal(first, again)
    assert not np.allclose(first, other)


def test_a_ring_in_a_batch_moves_exactly_as_the_same_ring_alone() -> None:
    plan = ring_plan(wave())
    batch, alone = FastRings(plan, 4), FastRings(plan, 1)
    batch.reset(np.arange(4), [10, 11, 12, 13])
    alone.reset([0], [12])
    assert batch.state is not None and alone.state is not None
    assert batch.lengths[2] == alone.lengths[0]
    accel = np.linspace(-1, 1, 300)
    for a in accel:
        batch.step(np.full((1, 4), a))
        alone.step(np.full((1, 1), a))
    assert np.array_equal(batch.state.speed[:, 2], alone.state.speed[:, 0])
    assert len(set(batch.lengths.tolist())) > 1  # the rings really differ


def test_horizon_truncates_and_the_ring_restarts_from_its_own_generator() -> None:
    cfg = wave("env.horizon=50", "env.warmup_steps=20")
    venv = RingVecEnv(ring_plan(cfg), 2)
    venv.seed(3)
    venv.reset()
    for _ in range(49):
        _, _, dones, _ = venv.step(np.zeros((2, 1)))
        assert not dones.any()
    obs, _, dones, infos = venv.step(np.zeros((2, 1)))
    assert dones.all()
    assert infos[0]["TimeLimit.truncated"] and not infos[0]["crash"]
    assert infos[0]["terminal_observation"].shape == (3,)
    assert 0 < infos[0]["mean_speed"] < 30
    # the second episode is the one a single env seeded 3 plays after its first
    single = RingEpisodes(ring_plan(cfg), 1)
    single.reset_all([3])
    for _ in range(50):
        second, *_ = single.step(np.zeros((1, 1)))
    assert np.array_equal(obs[0], second[0])


def test_cycle_seeds_repeat_the_same_episodes() -> None:
    cfg = wave("env.horizon=30", "env.warmup_steps=0")
    episodes = RingEpisodes(ring_plan(cfg), 1, cycle_seeds=(7, 8))
    starts = [episodes.reset_all([None])[0]]
    for _ in range(3):
        for _ in range(30):
            obs, *_ = episodes.step(np.zeros((1, 1)))
        starts.append(obs[0])
    assert np.array_equal(starts[0], starts[2]) and np.array_equal(starts[1], starts[3])
    assert not np.array_equal(starts[0], starts[1])


def test_a_collision_terminates_the_episode() -> None:
    cfg = wave("vehicles[1].car_following.speed_mode=aggressive", "env.warmup_steps=0")
    episodes = RingEpisodes(ring_plan(cfg), 1)
    episodes.reset_all([0])
    for step in range(3000):  # noqa: B007 - the step it ended at is checked
        _, reward, terminated, truncated, *_ = episodes.step(np.ones((1, 1)))
        if terminated[0]:
            break
    assert terminated[0] and not truncated[0] and step < 2999
    assert reward[0] == 0.0  # Flow's reward after a crash


def test_make_vec_env_builds_the_numpy_rings_with_a_monitor_file(tmp_path: Path) -> None:
    cfg = wave("env.horizon=20", "env.warmup_steps=0")
    venv = make_vec_env(cfg, 4, 0, monitor_dir=tmp_path)
    venv.reset()
    for _ in range(20):
        venv.step(np.zeros((4, 1)))
    venv.close()
    lines = (tmp_path / "rings.monitor.csv").read_text().splitlines()
    assert "mean_speed" in lines[1]
    assert len(lines) == 2 + 4  # header, columns, one episode per ring


def test_gymnasium_vector_env_resets_ended_rings_in_the_same_step() -> None:
    cfg = wave("env.horizon=10", "env.warmup_steps=0")
    env = RingVectorEnv(ring_plan(cfg), 3)
    obs, _ = env.reset(seed=1)
    assert obs.shape == (3, 3) and env.observation_space.contains(obs)
    for _ in range(9):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert "final_obs" not in info
    obs, reward, terminated, truncated, info = env.step(np.zeros((3, 1), np.float32))
    assert truncated.all() and not terminated.any()
    assert info["_final_obs"].all() and info["final_obs"][0].shape == (3,)
    assert reward.shape == (3,) and info["mean_speed"].shape == (3,)


def test_commands_that_run_on_sumo_only_refuse_a_numpy_config() -> None:
    from flowrun.fastring.plan import refuse_numpy_backend

    with pytest.raises(ConfigError, match="flowrun baseline runs on SUMO only"):
        refuse_numpy_backend(wave(), "flowrun baseline")
    refuse_numpy_backend(load("ring_wave"), "flowrun baseline")  # SUMO configs pass


def test_train_refuses_before_making_a_run_folder(tmp_path: Path) -> None:
    from flowrun.training.trainer import train

    with pytest.raises(ConfigError, match="single-lane"):
        train(wave("network.lanes=2"), out=tmp_path)
    assert not any(tmp_path.iterdir())


def test_baseline_of_a_numpy_config_is_refused_at_its_file_and_line(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from flowrun.cli.main import app

    config = Path("configs/ring_wave_numpy.yaml")
    line = config.read_text().splitlines().index("  backend: numpy") + 1
    result = CliRunner().invoke(app, ["baseline", str(config), "--out", str(tmp_path)])
    assert result.exit_code == 1
    assert f"{config}:{line}: sim.backend: flowrun baseline runs on SUMO only" in result.output
    assert not any(tmp_path.iterdir())
