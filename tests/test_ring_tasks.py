"""The ring tasks' one definition: a batch of rings gives each ring what a batch of one gives
it (no SUMO)."""

from __future__ import annotations

import numpy as np

from flowrun.envs.ring.tasks import (
    AccelTask,
    RingBatch,
    WavePOTask,
    full_observation,
    po_observation,
)


def rings(b: int, seed: int = 0) -> RingBatch:
    """``b`` rings of 5 cars with their own orders (leaders) and lengths."""
    rng = np.random.default_rng(seed)
    length = rng.uniform(220, 270, b)
    distance = np.sort(rng.uniform(0, 200, (5, b)), axis=0) + rng.uniform(0, 900, b)
    leader = np.vstack([np.arange(1, 6) % 5] * b).T  # each car's leader is the next one
    return RingBatch(rng.uniform(0, 10, (5, b)), distance, length, leader)


def column(batch: RingBatch, j: int) -> RingBatch:
    """Ring ``j`` of ``batch`` as a batch of one."""
    return RingBatch(batch.speed[:, j : j + 1], batch.distance[:, j : j + 1],
                     batch.length[j : j + 1], batch.leader[:, j : j + 1])  # fmt: skip


def test_a_batch_observes_each_ring_as_a_batch_of_one() -> None:
    batch = rings(4)
    task = WavePOTask({"max_accel": 1, "max_decel": 1}, 5, np.array([2]), 30.0, 270.0, False)
    obs = task.observe(batch)
    assert obs.shape == (3, 4)
    for j in range(4):
        assert obs[:, j].tolist() == task.observe(column(batch, j))[:, 0].tolist()
    full = full_observation(batch.speed, batch.position, 30.0, batch.length)
    assert full.shape == (10, 4) and full.min() >= 0.0 and full.max() <= 1.0


def test_the_partial_observation_is_speed_relative_speed_and_gap_to_the_leader() -> None:
    speed = np.array([[4.0], [6.0], [3.0]])
    distance = np.array([[10.0], [250.0], [500.0]])  # car 2 drove around once: 260 m on
    batch = RingBatch(speed, distance, 240.0, np.array([1, 2, 0]))
    obs = po_observation(batch, 2, 300.0)[:, 0]
    assert obs.tolist() == [3.0 / 15, (4.0 - 3.0) / 15, ((10.0 - 20.0) % 240.0) / 300.0]
    alone = RingBatch(speed, distance, 240.0, np.array([-1, -1, -1]))  # no leader: itself
    assert po_observation(alone, 0, 300.0)[:, 0].tolist() == [4.0 / 15, 0.0, 0.0]


def test_rewards_are_per_ring_and_zero_after_a_collision() -> None:
    batch = rings(3)
    task = AccelTask({"max_accel": 1, "max_decel": 1, "target_velocity": 10}, 5, np.array([0]),
                     30.0, 270.0, False)  # fmt: skip
    crashed = np.array([False, True, False])
    reward = task.rewards(batch, np.zeros((1, 3)), crashed)
    assert reward.shape == (3,) and reward[1] == 0.0 and (reward[[0, 2]] > 0).all()
    assert task.accelerations(np.array([[5.0], [-5.0], [0.5]]), clip=True).tolist() == [
        [1.0, -1.0, 0.5]
    ]
