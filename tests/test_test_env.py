"""Flow's ``TestEnv``: human drivers only, no actions, an optional reward function."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from flowrun.config.params import EnvParams
from flowrun.envs import TestEnv
from flowrun.envs.factory import make_network
from tests.conftest import load

pytestmark = pytest.mark.sumo


def test_test_env_runs_the_humans_and_rewards_with_the_given_function() -> None:
    cfg = load("sugiyama")
    params = EnvParams(horizon=100, additional_params={"reward_fn": lambda env: 7.0})
    env = TestEnv(params, cfg.sim, make_network(cfg))
    try:
        obs, _ = env.reset(seed=0)
        assert obs.shape == (0,)
        _, reward, terminated, _, _ = env.step(None)
        assert not terminated
        assert reward == 7.0
        for _ in range(99):
            *_, truncated, info = env.step(None)
        assert truncated and info["mean_speed"] > 0.5
    finally:
        env.close()


def test_test_env_passes_gymnasiums_checker_and_rewards_zero_by_default() -> None:
    cfg = load("sugiyama")
    env = TestEnv(EnvParams(horizon=50), cfg.sim, make_network(cfg))
    try:
        check_env(env, skip_render_check=True)
        env.reset(seed=0)
        assert env.step(np.zeros(0))[1] == 0.0
    finally:
        env.close()
