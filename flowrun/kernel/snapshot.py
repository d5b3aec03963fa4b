"""The vehicle population of an episode, and the pure geometry of who follows whom."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True)
class VehicleTable:
    """Static facts about every vehicle of an episode, in placement order.

    Attributes:
        ids: vehicle ids (``{group}_{i}``).
        types: group name of each vehicle.
        group: index of each vehicle's group in ``VehicleParams.groups``.
        is_rl: driven by the RL agent.
        commanded: a flowrun (non-SUMO, non-RL) controller sets its acceleration.
        continuous: routed by ``ContinuousRouter``.
        lengths: vehicle length, m.
        max_speeds: vehicle-type maximum speed, m/s.
        start_edges: edge each vehicle enters on.
        start_lane_pos: entry position on that edge, m.
        start_lanes: entry lane.
        initial_speeds: entry speed, m/s.
        speed_modes: SUMO speedMode of each vehicle.
        lane_change_modes: SUMO laneChangeMode of each vehicle.
    """

    ids: list[str]
    types: list[str]
    group: IntArray
    is_rl: BoolArray
    commanded: BoolArray
    continuous: BoolArray
    lengths: FloatArray
    max_speeds: FloatArray
    start_edges: list[str]
    start_lane_pos: list[float]
    start_lanes: list[int]
    initial_speeds: list[float]
    speed_modes: list[int]
    lane_change_modes: list[int]

    @property
    def size(self) -> int:
        """Number of vehicles."""
        return len(self.ids)


def leaders_on_ring(
    position: FloatArray, lanes: IntArray, lengths: FloatArray, ring_length: float
) -> tuple[IntArray, IntArray, FloatArray]:
    """Leader, follower and bumper-to-bumper headway of every car on a closed ring.

    Cars are sorted by position within each lane; each car's leader is the next one ahead
    (wrapping around the ring). A car alone in its lane has no leader (index -1, headway inf).

    Args:
        position: front-bumper position along the ring, m.
        lanes: lane index of each car.
        lengths: car lengths, m.
        ring_length: circumference, m.

    Returns:
        leader index, follower index (-1 for none) and headway (m) of every car.
    """
    n = position.shape[0]
    leader = np.full(n, -1, dtype=np.int64)
    follower = np.full(n, -1, dtype=np.int64)
    headway = np.full(n, np.inf)
    single_lane = n == 0 or lanes.min() == lanes.max()
    for lane in lanes[:1] if single_lane else np.unique(lanes):
        idx = np.arange(n) if single_lane else np.flatnonzero(lanes == lane)
        if idx.size < 2:
            continue
        idx = idx[np.argsort(position[idx], kind="stable")]
        ahead = np.concatenate((idx[1:], idx[:1]))
        leader[idx] = ahead
        follower[ahead] = idx
        headway[idx] = np.mod(position[ahead] - position[idx], ring_length) - lengths[ahead]
    return leader, follower, headway


class RingFollowing:
    """Who follows whom on a closed ring, reusing the last order while it still holds.

    On a single lane cars cannot pass, so the cyclic order found at the start stays valid; it
    is checked every step for the price of one sum (the gaps of a consistent cyclic order add
    up to exactly one ring length) and recomputed by :func:`leaders_on_ring` when it breaks.

    Attributes:
        complete: every car has a leader and a follower (single lane, two cars or more).
    """

    def __init__(self, lengths: FloatArray, ring_length: float) -> None:
        self.lengths = lengths
        self.ring_length = ring_length
        self.complete = False
        self._leader: IntArray | None = None
        self._follower: IntArray | None = None

    def compute(
        self, position: FloatArray, lanes: IntArray
    ) -> tuple[IntArray, IntArray, FloatArray]:
        """Leader index, follower index and headway (m) of every car."""
        n = position.shape[0]
        single = n >= 2 and lanes.min() == lanes.max()
        if single and self._leader is not None and self._follower is not None:
            gap = np.mod(position[self._leader] - position, self.ring_length)
            if abs(float(gap.sum()) - self.ring_length) < 1e-6 * self.ring_length:
                return self._leader, self._follower, gap - self.lengths[self._leader]
        leader, follower, headway = leaders_on_ring(position, lanes, self.lengths, self.ring_length)
        self.complete = single
        self._leader, self._follower = (leader, follower) if single else (None, None)
        return leader, follower, headway
