"""The list functions for few cars give the numpy functions' leaders, gaps and followers."""

from __future__ import annotations

import numpy as np

from flowrun.kernel.following import followers_small, leaders_by_lane, leaders_small
from flowrun.kernel.open_road import followers_of


def test_small_equals_numpy_on_random_roads() -> None:
    rng = np.random.default_rng(3)
    for _ in range(500):
        n = int(rng.integers(0, 40))
        key = rng.integers(0, 6, n)
        pos = np.round(rng.uniform(0, 60, n), int(rng.integers(0, 2)))  # ties too
        lengths = rng.choice([4.0, 5.0, 7.5], n)
        lead, _, head, fronts, rears = leaders_by_lane(key, pos, lengths)
        s_lead, s_head, s_fronts, s_rears = leaders_small(key.tolist(), pos.tolist(),
                                                          lengths.tolist())  # fmt: skip
        assert s_lead == lead.tolist() and s_fronts == fronts.tolist()
        assert s_rears == rears.tolist()
        assert np.array_equal(np.array(s_head), head)  # bit for bit (inf where none)
        # leaders past a lane's end, several cars with the same leader (merges), equal gaps
        for r in fronts.tolist():
            if n and rng.random() < 0.5:
                lead[r] = s_lead[r] = int(rng.integers(0, n))
                head[r] = s_head[r] = float(np.round(rng.uniform(0, 30)))
        follower, tailway = followers_of(lead, head)
        s_follower, s_tailway = followers_small(s_lead, s_head)
        assert s_follower == follower.tolist()
        assert np.array_equal(np.array(s_tailway), tailway)


def test_followers_small_nan_headway_as_numpy() -> None:
    nan = float("nan")
    lead, head = [2, 2, 2, -1], [nan, 5.0, nan, float("inf")]
    follower, tailway = followers_of(np.array(lead), np.array(head))
    s_follower, s_tailway = followers_small(lead, head)
    assert s_follower == follower.tolist() == [-1, -1, 1, -1]
    assert s_tailway[2] == tailway[2] == 5.0
