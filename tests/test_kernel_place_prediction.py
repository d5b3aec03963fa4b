"""On an open network with SUMO's Euler update, the kernel does not read the position of a car
that stays on the only lane of its edge: it is the last position plus ``speed * dt``. Every
step, every car's lane and position must still equal SUMO's ``getLaneID`` and
``getLanePosition`` bit for bit: on the figure eight (through its junction's internal
lanes, few cars: the list path) and on grid0 (cars entering and leaving, more cars than the
list path takes: the numpy path). A SUMO that does not move the cars so (the ballistic
update) is caught by the periodic check, after which every car is read."""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from flowrun.envs.factory import make_env
from flowrun.kernel.following import SMALL
from flowrun.kernel.open_reader import CHECK_EVERY
from flowrun.loading.loader import load_config

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def count_position_reads(env: Any) -> list[int]:
    """Wrap the kernel's lane-position getter; the returned list's one entry counts calls."""
    reader = env.k.vehicle.reader
    get, calls = reader.fast.get_lane_position, [0]

    def counted(vid: str) -> float:
        calls[0] += 1
        return float(get(vid))

    reader.fast = replace(reader.fast, get_lane_position=counted)
    return calls


def mismatches(env: Any) -> int:
    """Cars whose kernel lane or position differs from SUMO's now (bit for bit)."""
    vk = env.k.vehicle
    api = vk.api.vehicle
    names = vk.edge_names
    ours = zip(vk.get_ids(), vk.edge_index.tolist(), vk.lanes.tolist(), vk.lane_pos.tolist(),
               strict=True)  # fmt: skip
    return sum(
        f"{names[e]}_{lane}" != api.getLaneID(v) or pos != api.getLanePosition(v)
        for v, e, lane, pos in ours
    )


def run(env: Any, steps: int, seed: int = 0) -> tuple[int, int, int, int]:
    """Step ``env`` with seeded random actions, checking every car after every step.

    Returns:
        (cars compared, wrong, positions the kernel read, most cars at once).
    """
    env.reset(seed=seed)
    calls = count_position_reads(env)
    rng = np.random.default_rng(seed)
    shape = env.action_space.shape
    compared = wrong = most = 0
    for _ in range(steps):
        env.step(rng.uniform(-1, 1, shape).astype(np.float32) if shape else None)
        wrong += mismatches(env)
        n = env.k.vehicle.num_vehicles
        compared, most = compared + n, max(most, n)
    return compared, wrong, calls[0], most


@pytest.mark.sumo
def test_figure_eight_places_equal_sumos_with_few_reads() -> None:
    env = make_env(load_config(CONFIGS / "benchmarks" / "figureeight0.yaml",
                               ["env.horizon=1200"]))  # fmt: skip
    try:
        compared, wrong, reads, most = run(env, 1200)
        assert env.k.vehicle.reader.euler  # the check never found a difference
    finally:
        env.close()
    assert most == 14 and compared == 14 * 1200
    assert wrong == 0
    # cars near a lane's end, and every car at each check: a small share is read
    assert 0 < reads < compared // 10


@pytest.mark.sumo
def test_grid_places_equal_sumos_on_the_numpy_path() -> None:
    env = make_env(load_config(CONFIGS / "benchmarks" / "grid0.yaml", ["env.horizon=300"]))
    try:
        compared, wrong, reads, most = run(env, 300)
        assert env.k.vehicle.reader.euler
    finally:
        env.close()
    assert most > SMALL  # more cars than the list path takes
    assert wrong == 0
    assert 0 < reads < compared // 2


@pytest.mark.sumo
def test_a_step_method_other_than_euler_is_caught_and_every_car_read(
    caplog: pytest.LogCaptureFixture,
) -> None:
    cfg = load_config(CONFIGS / "benchmarks" / "figureeight0.yaml",
                      ["env.horizon=400", "sim.use_ballistic=true"])  # fmt: skip
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        reader = env.k.vehicle.reader
        assert not reader.euler  # the kernel knows the update is ballistic
        reader.euler = True  # as if it did not: positions predicted the Euler way
        rng = np.random.default_rng(0)
        shape = env.action_space.shape
        wrong_at = []
        with caplog.at_level(logging.WARNING, logger="flowrun.kernel.open_reader"):
            for i in range(2 * CHECK_EVERY + 2):
                env.step(rng.uniform(-1, 1, shape).astype(np.float32))
                if mismatches(env):
                    wrong_at.append(i)
        assert not reader.euler
    finally:
        env.close()
    assert "Euler" in caplog.text
    assert wrong_at and max(wrong_at) < CHECK_EVERY + 1  # right again from the first check
