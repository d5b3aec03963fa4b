"""The per-step vehicle state: neighbour fields from one function, open-road fields read once
when first asked (no SUMO: a reader that counts its reads)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from flowrun.kernel.following import leaders_on_ring, neighbours
from flowrun.kernel.state import OpenState
from flowrun.types import FloatArray, IntArray


def test_neighbour_speeds_and_gaps_follow_from_who_follows_whom() -> None:
    speed = np.array([1.0, 2.0, 3.0])
    leader, follower = np.array([1, -1, 1]), np.array([-1, 0, -1])
    headway = np.array([10.0, np.inf, 4.0])
    near = neighbours(speed, leader, follower, headway)
    assert near.leader_speed.tolist() == [2.0, 2.0, 2.0]  # no leader: the car's own speed
    assert near.follower_speed.tolist() == [1.0, 1.0, 3.0]
    assert near.follower_headway.tolist() == [np.inf, 10.0, np.inf]
    assert near.tailway is near.follower_headway


def test_a_complete_ring_gives_the_same_neighbours_with_or_without_the_checks() -> None:
    position = np.array([0.0, 30.0, 70.0, 100.0])
    lengths = np.full(4, 5.0)
    leader, follower, headway = leaders_on_ring(position, np.zeros(4, np.int64), lengths, 150.0)
    speed = np.array([3.0, 4.0, 5.0, 6.0])
    fast = neighbours(speed, leader, follower, headway, complete=True)
    checked = neighbours(speed, leader, follower, headway)
    for name in ("leader_speed", "follower_speed", "follower_headway", "tailway"):
        assert getattr(fast, name).tolist() == getattr(checked, name).tolist()
    assert fast.follower_headway.tolist() == [45.0, 25.0, 35.0, 25.0]


class CountingReader:
    """What an :class:`OpenState` asks its reader, counted."""

    def __init__(self) -> None:
        self.reads = {"place": 0, "xy": 0, "following": 0, "odometer": 0}
        self.lanes = SimpleNamespace(
            lane_index=np.array([0, 1]), start=np.array([100.0, 200.0]),
            speed_limit=np.array([10.0, 20.0]), internal=np.array([False, True]),
            edge_index=np.array([0, 1]), edge_names=["a", ":j"],
        )  # fmt: skip
        self.read_xy_each_step = False
        #: the lane keys of every read (the same array: no car changes lanes)
        self.keys = np.array([1, 0])
        self.columns: dict[str, object] = {}

    def read_place(self, speed: FloatArray) -> tuple[IntArray, FloatArray]:
        self.reads["place"] += 1
        return self.keys, np.array([5.0, 7.0])

    def columns_at(self, keys: IntArray) -> dict[str, object]:
        assert keys is self.keys
        return self.columns

    def read_xy(self) -> tuple[FloatArray, FloatArray]:
        self.reads["xy"] += 1
        return np.array([1.0, 2.0]), np.array([3.0, 4.0])

    def read_odometer(self) -> FloatArray:
        self.reads["odometer"] += 1
        return np.array([50.0, 60.0])

    def following(self, speed: FloatArray, lane_key: IntArray, lane_pos: FloatArray) -> object:
        self.reads["following"] += 1
        return neighbours(speed, np.array([-1, 0]), np.array([1, -1]), np.array([np.inf, 3.0]))


def test_open_state_reads_each_field_once_when_first_asked() -> None:
    reader = CountingReader()
    state = OpenState(np.array([8.0, 9.0]), np.array([7.0, 9.0]), 0.5, reader)  # type: ignore[arg-type]
    assert reader.reads == {"place": 0, "xy": 0, "following": 0, "odometer": 0}
    assert state.accel_real.tolist() == [2.0, 0.0]
    assert state.position.tolist() == [205.0, 107.0]  # edge start of each car's lane + lane pos
    assert state.speed_limit.tolist() == [20.0, 10.0]
    assert state.edges == [":j", "a"]
    assert state.lanes.tolist() == [1, 0]
    assert reader.reads["place"] == 1 and reader.reads["following"] == 0
    assert state.leader_speed.tolist() == [8.0, 8.0]
    assert state.headway.tolist() == [np.inf, 3.0]
    assert reader.reads["following"] == 1
    # a car on a junction-internal lane gets no command (SUMO drives it for that step)
    assert np.isnan(state.commandable(np.array([1.0, 1.0]), slice(None))).tolist() == [True, False]
    state.read_all()  # everything this step has not read (x, y only when read each step)
    assert reader.reads == {"place": 1, "xy": 0, "following": 1, "odometer": 0}
    assert state.x.tolist() == [1.0, 2.0] and state.odometer.tolist() == [50.0, 60.0]
    assert reader.reads == {"place": 1, "xy": 1, "following": 1, "odometer": 1}


def test_open_states_on_the_same_lane_keys_share_the_lane_columns_looked_up() -> None:
    reader = CountingReader()
    first = OpenState(np.array([8.0, 9.0]), np.array([7.0, 9.0]), 0.5, reader)  # type: ignore[arg-type]
    limit = first.speed_limit
    assert first.lanes.tolist() == [1, 0]
    assert first.commandable(np.array([1.0, 1.0]), slice(None)).tolist()[1] == 1.0
    second = OpenState(np.array([6.0, 9.0]), np.array([8.0, 9.0]), 0.5, reader)  # type: ignore[arg-type]
    second.lanes = np.array([3, 3])  # a field assigned before the lanes are read stays
    assert second.position.tolist() == [205.0, 107.0]
    assert second.speed_limit is limit and not limit.flags.writeable
    assert second.lanes.tolist() == [3, 3]
    assert np.isnan(second.commandable(np.array([1.0, 1.0]), slice(None))).tolist() == [True, False]
