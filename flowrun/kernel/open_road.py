"""Leaders and followers on any network: numpy within lanes, SUMO beyond a lane's ends.

Within a lane, cars are sorted by lane position (:func:`leaders_by_lane`). Only the frontmost
car of each occupied lane needs a look past the lane's end, along its route and through
junction-internal lanes; SUMO's ``getLeader`` gives exactly that (gap minus the ego's
``minGap``, which is added back). Likewise the rearmost car of each lane asks SUMO's
``getFollower`` (gap minus the *follower's* ``minGap``). So SUMO is asked twice per occupied
lane, not per car.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from flowrun.kernel.population import FloatArray, IntArray, Population
from flowrun.kernel.snapshot import leaders_by_lane

#: How far past the end (or before the start) of its lane a car looks for a leader
#: (follower), m. Beyond it IDM's interaction term is below (32 / 500)^2 = 0.4 %.
LOOKAHEAD = 500.0

Neighbour = Callable[[str, float], Any]


class Following:
    """Who follows whom on an open network.

    Attributes (after :meth:`compute`, one entry per live car):
        leader, follower: row of the car ahead / behind, -1 for none.
        headway: gap from the front bumper to the leader's rear bumper, m (``inf``: none).
        tailway: gap from the follower's front bumper to this car's rear bumper, m.
    """

    def __init__(self, get_leader: Neighbour, get_follower: Neighbour) -> None:
        self._get_leader = get_leader
        self._get_follower = get_follower

    @classmethod
    def of(cls, api: Any) -> Following:
        """Bound to ``libsumo``'s compiled calls (or ``traci``'s)."""
        raw = getattr(api, "_libsumo", None)
        if raw is not None and hasattr(raw, "vehicle_getLeader"):
            return cls(raw.vehicle_getLeader, raw.vehicle_getFollower)
        return cls(api.vehicle.getLeader, api.vehicle.getFollower)

    def compute(
        self, pop: Population, lane_key: IntArray, lane_pos: FloatArray
    ) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
        """Leader, follower, headway and tailway of every live car."""
        lengths, min_gaps, ids = pop.lengths, pop.min_gaps, pop.ids
        leader, follower, headway, fronts, rears = leaders_by_lane(lane_key, lane_pos, lengths)
        has_follower = follower >= 0
        tailway = np.where(has_follower, headway[np.where(has_follower, follower, 0)], np.inf)
        get_leader, get_follower = self._get_leader, self._get_follower
        for r in fronts.tolist():
            found = get_leader(ids[r], LOOKAHEAD)
            if found and found[0] and found[0] in pop:
                leader[r] = pop.row(found[0])
                headway[r] = float(found[1]) + float(min_gaps[r])
        for r in rears.tolist():
            found = get_follower(ids[r], LOOKAHEAD)
            if found and found[0] and found[0] in pop:
                j = pop.row(found[0])
                follower[r] = j
                tailway[r] = float(found[1]) + float(min_gaps[j])
        return leader, follower, headway, tailway
