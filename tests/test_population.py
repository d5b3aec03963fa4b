"""The population table: rows follow cars entering and leaving, in one update."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from flowrun.kernel.population import FOREIGN, Population, VehicleClass


def _classes() -> tuple[VehicleClass, VehicleClass]:
    return replace(FOREIGN, name="human", length=5.0), replace(
        FOREIGN, name="av", is_rl=True, length=4.0
    )


def test_change_keeps_survivor_order_appends_new_cars_and_maps_old_rows() -> None:
    pop = Population(_classes())
    pop.add(["a", "b", "c", "d"], [0, 1, 0, 0])
    src = pop.change(["b", "zz"], ["e", "c"], [1, 0])  # "zz" unknown, "c" already there
    assert pop.ids == ["a", "c", "d", "e"]
    assert src is not None and src.tolist() == [0, 2, 3, -1]
    assert pop.is_rl.tolist() == [False, False, False, True]
    assert pop.lengths.tolist() == [5.0, 5.0, 5.0, 4.0]
    assert [pop.row(v) for v in pop.ids] == [0, 1, 2, 3]
    assert "b" not in pop and "e" in pop


def test_change_reuses_freed_slots_and_reports_no_change() -> None:
    pop = Population(_classes())
    pop.add(["a", "b"], [0, 0])
    version = pop.version
    assert pop.change(["x"], [], []) is None and pop.version == version
    pop.change(["a"], ["c"], [1])
    assert pop.ids == ["b", "c"]
    assert pop.rows(["c", "b"]).tolist() == [1, 0]
    assert np.array_equal(pop.group, [0, 1])
    assert pop.types == ["human", "av"]
