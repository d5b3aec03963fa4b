"""Per-step speed statistics (pure): the numbers ``metrics.json`` and ``/flowrun/stats`` hold."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowrun.envs.frames import speed_stats


@pytest.mark.parametrize("n", [1, 2, 22, 64, 65, 2200])
def test_speed_stats_equal_numpy_on_both_sides_of_the_small_ring_shortcut(n: int) -> None:
    speed = np.random.default_rng(n).uniform(0.0, 30.0, n)
    count, mean, low, high, std = speed_stats(speed)
    assert count == n
    assert mean == pytest.approx(float(np.mean(speed)), rel=1e-13)
    assert (low, high) == (float(speed.min()), float(speed.max()))
    assert std == pytest.approx(float(np.std(speed)), rel=1e-12, abs=1e-13)


def test_speed_stats_of_a_uniform_flow_have_zero_spread() -> None:
    assert speed_stats(np.full(22, 3.454)) == (22, 3.454, 3.454, 3.454, 0.0)


def test_speed_stats_of_an_empty_network_are_nan() -> None:
    count, *rest = speed_stats(np.zeros(0))
    assert count == 0
    assert all(math.isnan(x) for x in rest)
