"""Per-step speed statistics (pure): the numbers ``metrics.json`` and ``/flowrun/stats`` hold."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowrun.envs.frames import StepRecord, batch_stats
from flowrun.experiment.metrics import RunAccumulator


def records(sizes: list[int], seed: int = 0) -> list[StepRecord]:
    rng = np.random.default_rng(seed)
    return [
        StepRecord(step, step / 10, rng.uniform(0.0, 30.0, n), step % 3 == 0, 0, None, step * 0.5)
        for step, n in enumerate(sizes)
    ]


@pytest.mark.parametrize(
    "sizes", [[22] * 300, [1, 2, 2200], [3, 5, 5, 0, 0, 4]], ids=["ring", "sizes", "changing"]
)
def test_a_batch_holds_each_steps_own_statistics(sizes: list[int]) -> None:
    recs = records(sizes)
    rows = batch_stats(recs).rows()
    assert [r.step for r in rows] == list(range(len(sizes)))
    for rec, row in zip(recs, rows, strict=True):
        speed = rec.speed
        assert (row.num_vehicles, row.time, row.reward) == (speed.size, rec.time, rec.reward)
        assert (row.collisions, row.teleports) == (rec.collisions, 0)
        if speed.size:
            assert (row.min_speed, row.max_speed) == (float(speed.min()), float(speed.max()))
            assert row.mean_speed == pytest.approx(float(np.mean(speed)), rel=1e-13)
            assert row.speed_std == pytest.approx(float(np.std(speed)), rel=1e-12, abs=1e-13)
        else:
            assert math.isnan(row.mean_speed) and math.isnan(row.speed_std)
            assert math.isnan(row.min_speed) and math.isnan(row.max_speed)


def test_batches_fold_into_the_same_run_metrics_as_one_batch() -> None:
    recs = records([22] * 1000, seed=4)
    whole, pieces = RunAccumulator(), RunAccumulator()
    whole.add_batch(batch_stats(recs))
    for i in range(0, 1000, 256):
        pieces.add_batch(batch_stats(recs[i : i + 256]))
    assert pieces.result(0, 1.0) == whole.result(0, 1.0)
    means = [float(np.mean(r.speed)) for r in recs]
    result = whole.result(0, 1.0)
    assert result.steps == 1000 and result.collisions == 334
    assert result.last_half_mean_speed == pytest.approx(np.mean(means[500:]), rel=1e-12)
    assert result.min_speed == min(float(r.speed.min()) for r in recs)
