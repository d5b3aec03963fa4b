"""``bench/learning_speed.py``: SUMO alone replays the env's traffic; the table's columns."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

BENCH = Path(__file__).resolve().parent.parent / "bench"


def _bench(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, BENCH / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault(name, module)
    spec.loader.exec_module(module)
    return module


ls = _bench("learning_speed")
evs = sys.modules["env_vs_sumo"]


@pytest.mark.parametrize(("name", "domain"), [("merge0", "vehicle"), ("grid0", "trafficlight")])
def test_sumo_alone_replays_the_envs_car_count_at_every_step(name: str, domain: str) -> None:
    log, counts = evs.record(name, 120)
    assert len(log) == len(counts) >= 120  # one entry per simulation step
    assert max(counts) > min(counts)  # cars entered or left: the count is a real check
    assert any(d == domain for calls in log for d, *_ in calls)  # e.g. grid0's signal states
    env = evs.make(name, 120)
    try:
        assert evs.replay(env.k.process.api, log, count=True) == counts
    finally:
        env.close()


def test_table_ratios_and_targets_come_from_the_measured_values() -> None:
    fast = ls.Row(ls.Throughput("a", 1000.0, 1300.0, ""), evs.Comparison(
        [(90.0, 30.0), (100.0, 40.0), (80.0, 20.0)], 14.0, 13.0, True), 0.5)  # fmt: skip
    slow = ls.Row(ls.Throughput("b", 2000.0, 1000.0, ""), evs.Comparison(
        [(310.0, 100.0)], 44.0, 6.0, False), 1.5)  # fmt: skip
    head, _, row_a, row_b = ls.table([fast, slow], cores=2)
    assert "≥ 1.2" in head
    cells_a = [c.strip() for c in row_a.strip("|").split("|")]
    assert cells_a == ["a", "1,000", "1,300", "1.30", "yes", "90", "30", "3.00", "yes",
                       "14 (yes)", "0.50"]  # fmt: skip
    cells_b = [c.strip() for c in row_b.strip("|").split("|")]
    assert cells_b[3:5] == ["0.50", "no"]
    assert cells_b[5:10] == ["310", "100", "3.10", "no", "44 (NO)"]


def test_update_steps_follow_the_recipe() -> None:
    from flowrun.loading.loader import load_config

    ars = load_config(evs.CONFIGS / "grid0.yaml")  # 2 x 16 candidates of one 400-step episode
    ppo = load_config(evs.CONFIGS / "merge0.yaml")  # 750 steps on each of 2 envs
    assert (ls.update_steps(ars), ls.update_steps(ppo)) == (12_800, 1_500)
