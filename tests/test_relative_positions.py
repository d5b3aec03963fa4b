"""AccelEnv's ``relative_positions`` option: positions measured from the first RL car."""

from __future__ import annotations

import numpy as np

from flowrun.envs.factory import make_env
from flowrun.envs.ring.accel import from_first_rl
from flowrun.loading.loader import load_config

FIGURE_EIGHT = "configs/benchmarks/figureeight0.yaml"


def test_positions_forward_from_the_first_rl_car_modulo_the_length() -> None:
    pos = np.array([10.0, 400.0, 50.0, 390.0])
    out = from_first_rl(pos, np.array([False, True, False, True]), 421.9)
    np.testing.assert_allclose(out, [31.9, 400.0, 71.9, 411.9])
    no_rl = from_first_rl(pos, np.zeros(4, dtype=bool), 421.9)
    np.testing.assert_array_equal(no_rl, pos)


def _rollout(overrides: list[str]) -> tuple[list[np.ndarray], list[float], np.ndarray, float]:
    env = make_env(load_config(FIGURE_EIGHT, overrides))
    try:
        obs, _ = env.reset(seed=3)
        observations, rewards = [obs], []
        for step in range(60):
            obs, reward, *_ = env.step(np.array([1.5 if step < 40 else -1.0]))
            observations.append(obs)
            rewards.append(float(reward))
        x = env.k.vehicle.position.copy()
        return observations, rewards, x, env.k.network.length()
    finally:
        env.close()


def test_figure_eight_observes_gaps_from_the_av_and_drives_the_same() -> None:
    plain_obs, plain_rewards, x, length = _rollout([])
    rel_obs, rel_rewards, x_rel, _ = _rollout(["env.additional_params.relative_positions=true"])
    np.testing.assert_array_equal(x, x_rel)  # the same traffic
    assert rel_rewards == plain_rewards
    n = 14
    for plain, rel in zip(plain_obs, rel_obs, strict=True):
        np.testing.assert_array_equal(plain[:n], rel[:n])  # speeds unchanged
    positions = rel_obs[-1][n:] * length
    av = 13  # the last car is the AV
    expected = np.mod(x - x[av], length)
    expected[av] = x[av]
    np.testing.assert_allclose(positions, expected, atol=1e-9)
    assert 0.0 < positions[0] < length / 2  # the AV's leader: the first car, ahead of it
