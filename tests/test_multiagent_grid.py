"""``MultiTrafficLightGridPOEnv`` on real SUMO (short, seeded): PettingZoo's parallel API test,
one agent per light, each light's observation recomputed from the kernel, switches applied to
the light that asked only, Flow's shared reward, same seed => same episode."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("pettingzoo")

from pettingzoo.test import parallel_api_test

from flowrun.core import rewards
from flowrun.envs.factory import make_env
from flowrun.envs.signals import relative_node
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
GRID = CONFIGS / "multiagent_grid.yaml"


@contextmanager
def grid_env(*overrides: str) -> Iterator[Any]:
    env = make_env(load_config(GRID, ["env.horizon=30", *overrides]))
    try:
        yield env
    finally:
        env.close()


def test_neighbours_follow_flows_numbering() -> None:
    # 3 x 3: center4 is in the middle; center0 bottom left; center8 top right
    assert [relative_node(4, s, 3, 3) for s in ("top", "bottom", "left", "right")] == [
        7, 1, 3, 5,
    ]  # fmt: skip
    assert [relative_node(0, s, 3, 3) for s in ("top", "bottom", "left", "right")] == [
        3, -1, -1, 1,
    ]  # fmt: skip
    assert [relative_node(5, s, 2, 3) for s in ("top", "bottom", "left", "right")] == [
        -1, 2, 4, -1,
    ]  # fmt: skip
    with pytest.raises(NotImplementedError, match="'blah'"):  # Flow's error type
        relative_node(0, "blah", 3, 3)


@pytest.mark.sumo
def test_parallel_api_and_one_agent_per_light() -> None:
    with grid_env() as env:
        parallel_api_test(env, num_cycles=40)
        assert env.possible_agents == [f"center{i}" for i in range(9)]
        obs, _ = env.reset(seed=1)
        assert env.agents == env.possible_agents
        assert all(o.shape == (42,) for o in obs.values())
        assert env.action_space("center3").shape == (1,)


@pytest.mark.sumo
def test_observation_recomputed_from_the_kernel() -> None:
    with grid_env() as env:
        env.reset(seed=3)
        for _ in range(12):
            obs, *_ = env.step({a: np.array([0.0], np.float32) for a in env.agents})
        vk, net = env.k.vehicle, env.k.network
        mapping = dict(env.network.node_mapping)
        edges = list(vk.edges)
        speeds = np.asarray(vk.speed, dtype=np.float64)
        for light in ("center4", "center0"):
            got = obs[light]
            incoming = mapping[light]
            # density and mean speed of the 4 incoming edges (values 24..31)
            for j, edge in enumerate(incoming):
                on = [i for i, e in enumerate(edges) if e == edge]
                assert got[24 + j] == pytest.approx(5 * len(on) / net.edge_length(edge), abs=1e-6)
                mean = speeds[on].mean() / net.max_speed() if on else 0.0
                assert got[28 + j] == pytest.approx(mean, abs=1e-6)
            # the nearest car on the first incoming edge: its speed and distance
            ids = vk.get_ids_by_edge(incoming[0])
            if ids:
                near = max(ids, key=vk.get_position)
                assert got[0] == pytest.approx(vk.get_speed(near) / net.max_speed(), abs=1e-6)
                dist = (net.edge_length(incoming[0]) - vk.get_position(near)) / env.max_dist
                assert got[8] == pytest.approx(dist, abs=1e-6)
            else:  # Flow's padding: a fast, far car on no edge
                assert (got[0], got[8], got[16]) == (1.0, 1.0, 0.0)
        # center0 has no neighbour below or on its left: direction 0, yellow 1 there
        assert list(obs["center0"][32:37]) == [0, 0, 0, 0, 0]
        assert list(obs["center0"][37:42]) == [0, 0, 1, 1, 0]


@pytest.mark.sumo
def test_only_the_light_that_asks_switches_and_reward_is_shared() -> None:
    with grid_env("env.additional_params.tl_type=controlled") as env:
        env.reset(seed=0)
        actions = {a: np.array([-1.0], np.float32) for a in env.agents}
        actions["center4"] = np.array([1.0], np.float32)
        obs, rew, term, trunc, _ = env.step(actions)
        yellow = env.timers.currently_yellow
        assert yellow[env.light_ids.index("center4")] == 1 and yellow.sum() == 1
        # center4 sees itself yellow; center7 (above it) sees center4 as its bottom neighbour
        assert obs["center4"][37] == 1 and obs["center7"][39] == 1 and obs["center7"][37] == 0
        assert env.k.traffic_light.get_state("center4").count("y") > 0
        assert "y" not in env.k.traffic_light.get_state("center1")
        expected = (-rewards.min_delay_unscaled(env) + rewards.penalize_standstill(env, 0.2)) / 9
        assert len(set(rew.values())) == 1
        assert rew["center0"] == pytest.approx(expected)
        assert not any(term.values()) and not any(trunc.values())


@pytest.mark.sumo
def test_same_seed_same_episode() -> None:
    def episode() -> list[float]:
        with grid_env() as env:
            obs, _ = env.reset(seed=7)
            rng = np.random.default_rng(0)
            out = [float(obs["center2"].sum())]
            while not env.episode_over:
                acts = {a: rng.uniform(-1, 1, 1).astype(np.float32) for a in env.agents}
                obs, rew, *_ = env.step(acts)
                out += [float(sum(rew.values())), float(obs["center2"].sum())] if obs else []
            return out

    first = episode()
    assert len(first) == 1 + 2 * 30
    assert first == episode()


def test_only_four_local_lights_and_edges() -> None:
    with pytest.raises(ConfigError, match=r"num_local_lights.*only 4"):
        make_env(load_config(GRID, ["env.additional_params.num_local_lights=2"]))
