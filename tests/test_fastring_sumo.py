"""The numpy ring backend against the SUMO backend: every car, every step, same seed.

Tolerance 1e-9 m/s (SUMO rounds its own arithmetic slightly differently; measured ~1e-11).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from flowrun.envs.factory import make_env
from flowrun.fastring.plan import ring_plan
from flowrun.fastring.rings import FastRings
from flowrun.fastring.vec_env import RingEpisodes
from tests.conftest import load

pytestmark = pytest.mark.sumo

TOL = 1e-9


def sumo_rollout(cfg: Any, seed: int, actions: np.ndarray | None, steps: int) -> dict[str, Any]:
    """Speeds, positions, observations, rewards and end flags of the SUMO env."""
    env = make_env(cfg)
    try:
        obs, _ = env.reset(seed=seed)
        vk = env.k.vehicle
        out: dict[str, list[Any]] = {
            "v": [vk.speed.copy()],
            "x": [vk.position.copy()],
            "obs": [obs],
            "r": [],
            "end": [],
        }
        for t in range(steps):
            obs, r, term, trunc, _ = env.step(None if actions is None else actions[t])
            out["v"].append(env.k.vehicle.speed.copy())
            out["x"].append(env.k.vehicle.position.copy())
            out["obs"].append(obs)
            out["r"].append(r)
            out["end"].append((term, trunc))
            if term or trunc:
                break
        return {k: np.array(v) for k, v in out.items()}
    finally:
        env.close()


def fast_rollout(cfg: Any, seed: int, actions: np.ndarray | None, steps: int) -> dict[str, Any]:
    """The same quantities from one numpy ring (physics only: no observation)."""
    plan = ring_plan(cfg)
    rings = FastRings(plan, 1)
    rings.reset([0], [seed])
    assert rings.state is not None
    v, x = [rings.state.speed[:, 0].copy()], [rings.state.position[:, 0].copy()]
    crashed = []
    for t in range(steps):
        a = None if actions is None else np.clip(actions[t], -1.0, 1.0).reshape(-1, 1)
        crashed.append(bool(rings.step(a)[0]))
        v.append(rings.state.speed[:, 0].copy())
        x.append(rings.state.position[:, 0].copy())
    return {"v": np.array(v), "x": np.array(x), "crash": np.array(crashed)}


@pytest.mark.parametrize("name", ["sugiyama", "sugiyama_noise"])
def test_all_human_ring_equals_sumo_every_car_every_step(name: str) -> None:
    cfg = load(name)
    sumo = sumo_rollout(cfg, 0, None, 3000)
    fast = fast_rollout(cfg, 0, None, 3000)
    assert sumo["v"].shape == fast["v"].shape == (3001, 22)
    assert np.abs(sumo["v"] - fast["v"]).max() < TOL
    assert np.abs(sumo["x"] - fast["x"]).max() < 1e-8
    assert sumo["v"][1500:].mean() < 3.0  # the stop-and-go wave, not a trivial trajectory


def test_rl_car_with_right_of_way_is_capped_by_sumos_safe_speed_as_on_sumo() -> None:
    cfg = load("ring_wave", "env.horizon=3000")
    actions = np.ones((3000, 1))  # full throttle into the wave: SUMO's cap must hold it back
    sumo = sumo_rollout(cfg, 3, actions, 3000)
    fast = fast_rollout(cfg, 3, actions, 3000)
    assert sumo["v"].shape == fast["v"].shape == (3001, 22)
    assert np.abs(sumo["v"] - fast["v"]).max() < TOL  # row 0: after the IDM-driven warm-up
    rl = 21
    wanted = np.minimum(fast["v"][:-1, rl] + 0.1, 30.0)
    capped = fast["v"][1:, rl] < wanted - 1e-6
    assert capped.sum() > 100  # the cap really acted
    assert not sumo["end"][:, 0].any()  # and no collision


def test_rl_car_without_safe_speed_crashes_at_the_same_step_as_on_sumo() -> None:
    cfg = load("ring_wave", "vehicles[1].car_following.speed_mode=aggressive")
    actions = np.ones((3000, 1))
    sumo = sumo_rollout(cfg, 3, actions, 3000)
    fast = fast_rollout(cfg, 3, actions, 3000)
    steps = len(sumo["r"])
    assert sumo["end"][-1][0] and steps < 3000  # SUMO reported a collision
    assert np.abs(sumo["v"] - fast["v"][: steps + 1]).max() < TOL
    assert int(np.argmax(fast["crash"])) == steps - 1


@pytest.mark.parametrize("env_class", ["WaveAttenuationPOEnv", "WaveAttenuationEnv", "AccelEnv"])
def test_observations_rewards_and_episode_end_equal_the_sumo_env(env_class: str) -> None:
    accel = ["target_velocity=10", "sort_vehicles=false"]
    extra = [f"env.additional_params.{a}" for a in accel] if env_class == "AccelEnv" else []
    cfg = load("ring_wave", f"env.class={env_class}", "env.horizon=400", *extra)
    actions = np.random.default_rng(4).uniform(-1.5, 1.5, size=(400, 1))
    sumo = sumo_rollout(cfg, 11, actions, 400)
    episodes = RingEpisodes(ring_plan(cfg), 2)
    obs = [episodes.reset_all([11, 12])[0]]
    rewards, ends = [], []
    for t in range(400):
        o, r, term, trunc, final, _ = episodes.step(np.repeat(actions[t][None], 2, axis=0))
        obs.append(final[0] if term[0] or trunc[0] else o[0])
        rewards.append(r[0])
        ends.append((term[0], trunc[0]))
    assert np.abs(sumo["obs"] - np.array(obs)).max() < 1e-6  # float32 observations
    assert np.abs(sumo["r"] - np.array(rewards)).max() < 1e-9
    assert [tuple(e) for e in sumo["end"]] == ends
    assert ends[-1] == (False, True)


def test_a_numpy_episode_log_holds_what_the_sumo_baseline_log_holds(tmp_path: Any) -> None:
    from flowrun.experiment.baseline import run_baseline
    from flowrun.fastring.record import record_episode
    from flowrun.recording import open_log

    cfg = load("sugiyama_noise", "env.horizon=300")
    sumo_dir = run_baseline(cfg, runs=1, out=tmp_path / "sumo").run_dir
    sumo_log = open_log(next(sumo_dir.glob("*.mcap")))
    path = tmp_path / "numpy.mcap"
    assert record_episode(cfg, path, seed=0) == 0.0
    log = open_log(path)
    sumo_frames, frames = list(sumo_log.frames()), list(log.frames())
    assert len(frames) == len(sumo_frames) == 301
    for ours, theirs in zip(frames, sumo_frames, strict=True):
        assert ours.step == theirs.step and ours.ids == theirs.ids and ours.edges == theirs.edges
        assert ours.time == pytest.approx(theirs.time)
        assert np.abs(ours.speed - theirs.speed).max() < TOL
        assert np.abs(ours.lane_pos - theirs.lane_pos).max() < 1e-8
        assert ours.leader == theirs.leader
        assert np.allclose(ours.accel_cmd, theirs.accel_cmd, atol=1e-9, equal_nan=True)
    stats, sumo_stats = list(log.stats()), list(sumo_log.stats())
    assert [s.mean_speed for s in stats] == pytest.approx([s.mean_speed for s in sumo_stats])
    assert log.metadata["network_length"] == sumo_log.metadata["network_length"]
    assert log.metadata["edge_starts"] == sumo_log.metadata["edge_starts"]


@pytest.mark.parametrize("controller", ["BCM", "OVM", "LinearOVM", "Gipps"])
def test_other_car_following_formulas_equal_sumo_too(controller: str) -> None:
    cfg = load("sugiyama_noise", f"vehicles[0].acceleration_controller={{type: {controller}}}")
    sumo = sumo_rollout(cfg, 2, None, 1000)
    fast = fast_rollout(cfg, 2, None, 1000)
    steps = len(sumo["r"])  # some of these models crash with Flow's defaults and noise
    assert np.abs(sumo["v"] - fast["v"][: steps + 1]).max() < TOL
    assert np.abs(np.diff(sumo["v"], axis=0)).max() > 0.01  # the cars really move
    crashed = bool(sumo["end"][-1][0])
    assert fast["crash"][:steps].any() == crashed
    if crashed:
        assert int(np.argmax(fast["crash"])) == steps - 1
