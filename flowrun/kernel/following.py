"""Who follows whom, as pure array functions: on a ring, within the lanes of any network, and
the gaps and speeds around every car that follow from it (:func:`neighbours`, for both)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flowrun.types import FloatArray, IntArray


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
    """Who follows whom on a closed single-lane ring, reusing the order while it holds.

    Cars cannot pass on a single lane, so the cyclic order found at the start stays valid.
    Headways come from the *unwrapped* positions ``u`` (entry position + distance driven, never
    taken modulo the ring length): ``h = u[leader] - u + wrap - length[leader]``, where ``wrap``
    (a whole number of ring lengths: one for the car whose leader is the rearmost car, else 0)
    is fixed when the order is found. A car that got past its leader (a collision SUMO let
    through) shows a gap below minus its leader's length; the order is then found anew by
    :func:`leaders_on_ring`.

    Attributes:
        complete: every car has a leader and a follower (two cars or more).
    """

    def __init__(self, lengths: FloatArray, ring_length: float) -> None:
        self.lengths = lengths
        self.ring_length = ring_length
        self.complete = False
        self._order: tuple[IntArray, IntArray, FloatArray, FloatArray] | None = None
        same = lengths.size == 0 or bool(np.all(lengths == lengths[0]))
        self._one_length = float(lengths[0]) if same and lengths.size else None

    def compute(self, unwrapped: FloatArray) -> tuple[IntArray, IntArray, FloatArray]:
        """Leader index, follower index and headway (m) of every car.

        Args:
            unwrapped: entry position + distance driven of every car, m (not wrapped).
        """
        if self._order is not None:
            leader, follower, offset, neg_length = self._order
            headway = unwrapped[leader] - unwrapped + offset
            length = self._one_length
            if length is not None:
                if headway.min() >= -length:
                    return leader, follower, headway
            elif not (headway < neg_length).any():
                return leader, follower, headway
        ring = self.ring_length
        n = unwrapped.shape[0]
        leader, follower, headway = leaders_on_ring(
            np.mod(unwrapped, ring), np.zeros(n, dtype=np.int64), self.lengths, ring
        )
        self.complete = n >= 2
        self._order = None
        if self.complete:
            ahead = unwrapped[leader] - unwrapped
            wrap = ring * np.round((np.mod(ahead, ring) - ahead) / ring)
            lead_length = self.lengths[leader]
            self._order = (leader, follower, wrap - lead_length, -lead_length)
        return leader, follower, headway


def leaders_by_lane(
    lane_key: IntArray, lane_pos: FloatArray, lengths: FloatArray
) -> tuple[IntArray, IntArray, FloatArray, IntArray, IntArray]:
    """Leader, follower and headway of every car among the cars of its own lane.

    Cars are sorted by position within each lane (one ``lexsort``); each car's leader is the
    next one ahead on the lane. The frontmost car of a lane gets no leader here and the
    rearmost no follower: those are found beyond the lane's ends (along the route, through
    junctions) by the caller.

    Args:
        lane_key: integer id of each car's lane.
        lane_pos: front-bumper position of each car on its lane, m.
        lengths: car lengths, m.

    Returns:
        leader index, follower index (-1 for none), headway (m, ``inf`` without leader),
        the indices of the frontmost car of every occupied lane and of the rearmost.
    """
    n = lane_key.shape[0]
    leader = np.full(n, -1, dtype=np.int64)
    follower = np.full(n, -1, dtype=np.int64)
    headway = np.full(n, np.inf)
    if n == 0:
        empty = np.zeros(0, dtype=np.int64)
        return leader, follower, headway, empty, empty
    order = np.lexsort((lane_pos, lane_key))
    key = lane_key[order]
    same = key[1:] == key[:-1]
    ego, ahead = order[:-1][same], order[1:][same]
    leader[ego] = ahead
    follower[ahead] = ego
    headway[ego] = lane_pos[ahead] - lengths[ahead] - lane_pos[ego]
    fronts = order[np.concatenate((~same, [True]))]
    rears = order[np.concatenate(([True], ~same))]
    return leader, follower, headway, fronts, rears


#: Up to this many cars, :func:`leaders_small` and :func:`followers_small` (plain Python on
#: lists) are faster than the numpy functions, whose cost is mostly per call; above, numpy.
SMALL = 48
_INF = float("inf")


def leaders_small(
    lane_key: list[int], lane_pos: list[float], lengths: list[float]
) -> tuple[list[int], list[float], list[int], list[int]]:
    """:func:`leaders_by_lane` on lists, for few cars: the same leaders, the same headways
    (bit for bit: the same float operations in the same order), fronts and rears in the same
    order (by lane key); no followers (:func:`followers_small` finds them).

    Returns:
        leader rows (-1 for none), headways (m, ``inf`` without leader), the frontmost car of
        every occupied lane and the rearmost.
    """
    n = len(lane_key)
    leader, headway = [-1] * n, [_INF] * n
    fronts: list[int] = []
    rears: list[int] = []
    prev, prev_key, prev_pos = -1, -1, 0.0
    # by lane, then position, then row: the order of the stable lexsort
    for k, p, i in sorted(zip(lane_key, lane_pos, range(n), strict=True)):
        if k == prev_key and prev >= 0:
            leader[prev] = i
            headway[prev] = p - lengths[i] - prev_pos
        else:
            if prev >= 0:
                fronts.append(prev)
            rears.append(i)
        prev, prev_key, prev_pos = i, k, p
    if prev >= 0:
        fronts.append(prev)
    return leader, headway, fronts, rears


def followers_small(leader: list[int], headway: list[float]) -> tuple[list[int], list[float]]:
    """``followers_of`` (:mod:`flowrun.kernel.open_road`) on lists: of the cars whose leader
    a car is, the one with the smallest headway (the lower row on a tie; a NaN headway only
    where all are NaN, as numpy's sort puts NaN last)."""
    n = len(leader)
    follower, tailway = [-1] * n, [_INF] * n
    for i, lead in enumerate(leader):
        if lead >= 0:
            h, t = headway[i], tailway[lead]
            if follower[lead] < 0 or h < t or (t != t and h == h):
                follower[lead], tailway[lead] = i, h
    return follower, tailway


def _read_only(rows: list[int]) -> IntArray:
    out = np.array(rows, dtype=np.int64)
    out.flags.writeable = False  # kept from step to step: a change would outlive its step
    return out


@dataclass(eq=False)
class Links:
    """Who follows whom among few cars as index arrays (:meth:`of`), kept from step to step
    while the leaders stay: each neighbour value is then one ``take`` of the step's array.

    Attributes:
        leader_rows: every car's leader row (-1 for none), the list the links were made of.
        leader, follower: the same as arrays (read-only), and every car's follower.
        leader_or_self, follower_or_self: the leader's (follower's) row, the car's own
            without one.
        unfollowed: rows of the cars without a follower.
        one_to_one: no car is the leader of two (then the leaders alone give the followers).
        complete: every car has a leader and a follower.
    """

    leader_rows: list[int]
    leader: IntArray
    follower: IntArray
    leader_or_self: IntArray
    follower_or_self: IntArray
    unfollowed: IntArray
    one_to_one: bool
    complete: bool

    @classmethod
    def of(cls, leader: list[int], follower: list[int]) -> Links:
        """The links of every car's ``leader`` and ``follower`` row (-1 for none)."""
        led = [j for j in leader if j >= 0]
        unfollowed = [i for i, f in enumerate(follower) if f < 0]
        return cls(
            leader, _read_only(leader), _read_only(follower),
            _read_only([j if j >= 0 else i for i, j in enumerate(leader)]),
            _read_only([f if f >= 0 else i for i, f in enumerate(follower)]),
            _read_only(unfollowed), len(set(led)) == len(led),
            len(led) == len(leader) and not unfollowed,
        )  # fmt: skip

    def tailway(self, headway: FloatArray) -> FloatArray:
        """Every car's tailway: its follower's ``headway`` (``inf`` without a follower)."""
        tailway = headway[self.follower_or_self]
        if self.unfollowed.size:
            tailway[self.unfollowed] = np.inf
        return tailway

    def neighbours(self, speed: FloatArray, headway: FloatArray, tailway: FloatArray) -> Neighbours:
        """:func:`neighbours` of these links (the same values, fewer numpy calls)."""
        return Neighbours(
            self.leader, self.follower, headway, tailway, speed[self.leader_or_self],
            speed[self.follower_or_self], tailway,
        )  # fmt: skip


@dataclass(eq=False)
class Neighbours:
    """Who follows whom, and the gaps and speeds around every car.

    Attributes:
        leader, follower: row of the car ahead / behind, -1 for none.
        headway: gap from the front bumper to the leader's rear bumper, m (``inf``: none).
        tailway: gap from the follower's front bumper to this car's rear bumper, m.
        leader_speed, follower_speed: their speeds, m/s (the car's own without one).
        follower_headway: the follower's headway, m (the tailway; ``inf`` without one).
    """

    leader: IntArray
    follower: IntArray
    headway: FloatArray
    tailway: FloatArray
    leader_speed: FloatArray
    follower_speed: FloatArray
    follower_headway: FloatArray


def neighbours(
    speed: FloatArray,
    leader: IntArray,
    follower: IntArray,
    headway: FloatArray,
    tailway: FloatArray | None = None,
    complete: bool = False,
) -> Neighbours:
    """The neighbour speeds and the follower's gap of every car, from who follows whom.

    Args:
        speed: every car's speed, m/s.
        leader, follower: rows of the cars ahead and behind (-1 for none).
        headway: gap to the leader, m.
        tailway: gap of the follower to the car, m (``None``: the follower's headway).
        complete: every car has a leader and a follower (skips the checks for none).
    """
    if complete:
        follower_headway = headway[follower]
        return Neighbours(
            leader, follower, headway, follower_headway, speed[leader], speed[follower],
            follower_headway,
        )  # fmt: skip
    has_lead, has_fol = leader >= 0, follower >= 0
    leader_speed = np.where(has_lead, speed[leader], speed)
    follower_speed = np.where(has_fol, speed[follower], speed)
    if tailway is None:
        tailway = np.where(has_fol, headway[follower], np.inf)
    return Neighbours(leader, follower, headway, tailway, leader_speed, follower_speed, tailway)
