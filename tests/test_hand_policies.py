"""The pure rules of ``bench/hand_policies.py``: each hand policy's action from given state."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import numpy as np

NAN = float("nan")


def _bench() -> ModuleType:
    path = Path(__file__).resolve().parent.parent / "bench" / "hand_policies.py"
    spec = importlib.util.spec_from_file_location("hand_policies", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("hand_policies", module)
    spec.loader.exec_module(module)
    return module


hp = _bench()


def test_cap_deltas_bring_the_slowest_av_to_its_target_within_the_action_space() -> None:
    min_caps = np.array([23.0, 6.0, 5.0, NAN, 10.0])
    targets = np.array([5.0, 5.0, 5.0, 5.0, NAN])
    # 23 -> 5 is cut to -1.5; 6 -> 5 is -1; at 5 already: 0; no AV: 0; no target: release (+1.5)
    assert np.allclose(hp.cap_deltas(min_caps, targets, -1.5, 1.5), [-1.5, -1.0, 0.0, 0.0, 1.5])


def test_fixed_time_switches_every_light_first_then_each_period_after_its_offset() -> None:
    offsets = np.array([0.0, 5.0])
    switched = {t: hp.fixed_time_switch(t, 10, offsets) > 0 for t in range(26)}
    assert switched[0].all()  # the first step takes every light over
    assert [t for t in range(1, 26) if switched[t][0]] == [10, 20]
    assert [t for t in range(1, 26) if switched[t][1]] == [15, 25]


def test_queue_rule_switches_only_a_settled_green_facing_a_longer_red_queue() -> None:
    green = np.array([1.0, 1.0, 3.0, 1.0])
    red = np.array([4.0, 4.0, 3.0, 4.0])
    since = np.array([11.0, 6.0, 20.0, 20.0])
    yellow = np.array([0.0, 0.0, 0.0, 1.0])
    # light 0 switches; 1 has not held its green long enough; 2 has no longer queue; 3 is yellow
    assert list(hp.queue_switch(green, red, since, yellow, 8.0)) == [1.0, -1.0, -1.0, -1.0]


def test_meter_engages_above_its_threshold_and_releases_at_or_below_the_lower_one() -> None:
    assert hp.meter_engaged(False, 12.5, 12.0, 8.0)
    assert not hp.meter_engaged(False, 10.0, 12.0, 8.0)  # not yet engaged: stays off
    assert hp.meter_engaged(True, 10.0, 12.0, 8.0)  # engaged: holds until 8
    assert not hp.meter_engaged(True, 8.0, 12.0, 8.0)
    assert not hp.meter_engaged(True, 12.0, 12.0, 12.0)  # no hysteresis: on above 12 only
