"""Lane changes on an open road (Flow's highway): SUMO's lane changes of humans under Flow's
lane-change modes, RL lane changes through ``apply_lane_change`` held for
``lane_change_duration`` steps, ``get_last_lc``, and the counts. Real SUMO, seeded."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from flowrun.envs import LaneChangeAccelEnv
from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


@contextmanager
def highway(*overrides: str) -> Iterator[Any]:
    env = make_env(load_config(CONFIGS / "highway_lane_change.yaml", list(overrides)))
    try:
        yield env
    finally:
        env.close()


def human_lane_changes(seed: int, *overrides: str, steps: int = 200) -> list[list[str]]:
    """Who changed lane at each step, RL cars told to keep their lanes."""
    with highway(f"env.horizon={steps}", *overrides) as env:
        env.reset(seed=seed)
        keep = np.zeros(env.action_space.shape, dtype=np.float32)
        out = []
        for _ in range(steps):
            info = env.step(keep)[4]
            out.append(env.k.vehicle.get_lane_changes())
        assert env.k.vehicle.num_lane_changes == sum(len(c) for c in out)
        assert info["lane_changes"] == sum(len(c) for c in out)
        assert not any(v.startswith("rl") for c in out for v in c)
    return out


def test_humans_change_lanes_under_sumo_default_and_not_under_no_lc_safe() -> None:
    changes = human_lane_changes(0)
    assert sum(len(c) for c in changes) > 10
    assert human_lane_changes(0) == changes  # same seed, same lane changes
    frozen = human_lane_changes(
        0,
        "vehicles.0.lane_change.lane_change_mode=no_lc_safe",
        "vehicles.1.lane_change.lane_change_mode=no_lc_safe",
    )
    assert sum(len(c) for c in frozen) == 0


def test_highway_lane_change_env_is_gymnasium_clean() -> None:
    with highway("env.horizon=50") as env:
        assert isinstance(env, LaneChangeAccelEnv)
        assert env.observation_space.shape == (3 * 40,)
        assert env.action_space.shape == (2 * 4,)
        check_env(env, skip_render_check=True)


def test_rl_lane_change_is_held_for_lane_change_duration_steps() -> None:
    with highway("env.horizon=200") as env:
        env.reset(seed=0)
        vk = env.k.vehicle
        rl = vk.get_rl_ids()
        speed_up = np.tile([1.0, 0.0], len(rl)).astype(np.float32)
        for _ in range(60):  # get moving, no lane changes asked
            env.step(speed_up)
        assert all(vk.get_last_lc(v) == -np.inf for v in rl)
        assert vk.get_last_lc(vk.get_human_ids()[0]) == -1001  # Flow: RL cars only
        before = {v: vk.get_lane(v) for v in rl}
        left = np.tile([1.0, 1.0], len(rl)).astype(np.float32)
        _, reward, _, _, info = env.step(left)
        moved = [v for v in rl if vk.get_lane(v) != before[v]]
        assert moved, "no RL car could move left"
        now = env.time_counter
        for v in moved:
            assert vk.get_lane(v) == before[v] + 1
            assert vk.get_last_lc(v) == now
        terms = info["reward_terms"]
        assert terms["lane_change_penalty"] == pytest.approx(-0.1 * len(moved))
        assert reward == pytest.approx(terms["desired_velocity"] - 0.1 * len(moved))
        # asked to go back right at once: refused for lane_change_duration (5) steps, then
        # passed on to the kernel
        asked: list[dict[str, float]] = []
        apply = vk.apply_lane_change

        def spy(ids: Any, direction: Any) -> None:
            asked.append(dict(zip(ids, np.asarray(direction, dtype=float).tolist(), strict=True)))
            apply(ids, direction)

        vk.apply_lane_change = spy
        right = np.tile([0.0, -1.0], len(rl)).astype(np.float32)
        for _ in range(5):
            _, _, _, _, info = env.step(right)
            assert [vk.get_lane(v) for v in moved] == [before[v] + 1 for v in moved]
            assert all(vk.get_last_lc(v) == now for v in moved)
        env.step(right)
        assert [[a[v] for v in moved] for a in asked] == [[0.0] * len(moved)] * 5 + [
            [-1.0] * len(moved)
        ]


def test_lane_changes_get_the_same_step_whether_asked_every_step_or_not() -> None:
    def stamps(ask: bool) -> dict[str, int]:
        with highway("env.horizon=200") as env:
            env.reset(seed=0)
            vk = env.k.vehicle
            vk.lane_change_log()
            for step in range(1, 201):
                env.k.step()
                assert env.k.simulation.step_count == step
                if ask:
                    vk.get_lane_changes()
            return dict(vk.lane_change_log().last)

    asked = stamps(True)
    assert asked and all(1 <= s <= 200 for s in asked.values())
    assert stamps(False) == asked


def test_partially_observed_env_sees_each_rl_cars_neighbours_on_every_lane() -> None:
    with highway("env.class=LaneChangeAccelPOEnv", "env.horizon=100") as env:
        assert env.observation_space.shape == (4 * 4 * 4 + 4,)  # 4 AVs, 4 lanes
        check_env(env, skip_render_check=True)
        obs, _ = env.reset(seed=0)
        for _ in range(50):
            obs = env.step(np.tile([1.0, 0.0], 4).astype(np.float32))[0]
        vk, net = env.k.vehicle, env.k.network
        rl = next(v for v in env.sorted_ids if v in vk.get_rl_ids())
        lane = vk.get_lane(rl)
        ahead = obs[:4]  # the first AV's gaps ahead on lanes 0-3
        expected = vk.get_headway(rl) / net.length() if vk.get_leader(rl) else 1.0
        assert ahead[lane] == pytest.approx(min(expected, 1.0), rel=1e-5)
        assert obs[64] == pytest.approx(vk.get_speed(rl) / net.max_speed(), rel=1e-5)
        assert set(env.visible) <= set(vk.get_ids()) and env.visible
