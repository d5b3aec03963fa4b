"""The open-network kernel asks SUMO for a car's lane only when it may have changed, and is
never wrong about it: every step, every car's lane (and so its edge) equals SUMO's
``getLaneID``, on Flow's grid0 (one lane per edge: most cars carried over) and on a
multi-lane network (cars there are always read)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from flowrun.envs.factory import make_env
from flowrun.loading.loader import load_config

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def count_lane_reads(env: Any) -> list[int]:
    """Wrap the kernel's lane-id getter; the returned list's one entry counts its calls."""
    reader = env.k.vehicle.reader
    get, calls = reader.fast.get_lane_id, [0]

    def counted(vid: str) -> str:
        calls[0] += 1
        return str(get(vid))

    reader.fast = replace(reader.fast, get_lane_id=counted)
    return calls


def check_lanes(env: Any, steps: int, action: Any) -> tuple[int, int]:
    """Step ``env``; after each step compare every car's lane with SUMO's.

    Returns:
        (lanes compared, lane ids the kernel asked SUMO for).
    """
    vk = env.k.vehicle
    calls = count_lane_reads(env)
    compared = 0
    for i in range(steps):
        env.step(action(i))
        names = vk.edge_names
        ids = vk.get_ids()
        ours = [f"{names[e]}_{lane}" for e, lane in
                zip(vk.edge_index.tolist(), vk.lanes.tolist(), strict=True)]  # fmt: skip
        truth = [vk.api.vehicle.getLaneID(v) for v in ids]
        assert ours == truth, i
        assert vk.edges == [vk.api.vehicle.getRoadID(v) for v in ids], i
        compared += len(ids)
    return compared, calls[0]


@pytest.mark.sumo
def test_grid_lanes_equal_sumos_and_most_are_carried_over() -> None:
    cfg = load_config(CONFIGS / "grid0.yaml", ["env.horizon=300"])
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        rng = np.random.default_rng(0)
        n = env.action_space.shape[0]  # type: ignore[index]
        compared, reads = check_lanes(
            env, 300, lambda _: rng.uniform(-1, 1, n).astype(np.float32)
        )
    finally:
        env.close()
    assert compared > 300 * 40  # grid0 holds ~60 cars
    # cars crossing onto a new lane, and those that entered, are read: a small share
    assert 0 < reads < compared // 4


@pytest.mark.sumo
def test_multi_lane_cars_are_always_read() -> None:
    cfg = load_config(CONFIGS / "highway_ramps.yaml", ["env.horizon=150"])
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        multi = env.k.vehicle.lane_table.alone  # per lane key, plus False at the end
        assert not multi[:-1].all()  # some edges have several lanes
        compared, reads = check_lanes(env, 150, lambda _: None)
    finally:
        env.close()
    assert compared > 0 and reads > 0


@pytest.mark.sumo
def test_a_step_the_kernel_did_not_read_makes_it_read_every_lane() -> None:
    cfg = load_config(CONFIGS / "grid0.yaml", ["env.horizon=100"])
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        for _ in range(50):
            env.step(None)
        vk = env.k.vehicle
        calls = count_lane_reads(env)
        env.step(None)
        assert calls[0] < vk.num_vehicles // 2  # the usual step: few cars read, if any
        env.k.simulation.simulation_step()  # a SUMO step with no kernel update after it
        env.k.step()
        calls[0] = 0
        vk.edges  # noqa: B018 - reading the lanes is what is measured
        assert calls[0] == vk.num_vehicles  # positions two steps old prove nothing
    finally:
        env.close()
