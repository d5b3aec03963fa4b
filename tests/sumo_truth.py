"""Checks of flowrun's kernel against SUMO's own answers, shared by the network tests."""

from __future__ import annotations

import math
from typing import Any

import pytest


def compare_leaders_with_sumo(env: Any, steps: int) -> tuple[int, int]:
    """Step ``env`` ``steps`` times with no RL action; after each step, every car's leader and
    headway must equal SUMO's ``getLeader`` (gap plus the ego's minGap, within 1e-6 m), and a
    car SUMO sees no leader for must have none and an infinite headway.

    Returns:
        (cars compared, of those whose leader is on another edge).
    """
    vk = env.k.vehicle
    v = vk.api.vehicle
    compared = across_junction = 0
    for _ in range(steps):
        env.step(None)
        for vid in vk.get_ids():
            found = v.getLeader(vid, 500.0)
            ours = vk.get_leader(vid)
            if not found or not found[0]:
                assert ours is None, vid
                assert vk.get_headway(vid) == 1000.0  # Flow's value
                assert vk.headway[vk.table.row(vid)] == math.inf  # what controllers read
                continue
            assert ours == found[0], vid
            gap = found[1] + v.getMinGap(vid)
            assert vk.get_headway(vid) == pytest.approx(gap, abs=1e-6), vid
            compared += 1
            across_junction += vk.get_edge(vid) != vk.get_edge(ours)
    return compared, across_junction
