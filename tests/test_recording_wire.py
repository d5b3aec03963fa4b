"""Hand-written protobuf encoders: the same bytes as the protobuf library, for any frame."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import numpy as np
import pytest
from google.protobuf.internal import api_implementation

from flowrun.recording import schema, wire
from flowrun.recording.frames import StepStats, VehicleFrame
from flowrun.recording.synthetic import ring_frames, step_stats

STATS_FIELDS = [f.name for f in dataclasses.fields(StepStats)]


def library_frame_bytes(frame: VehicleFrame, roster_version: int) -> bytes:
    """What the protobuf library writes for ``frame`` (the encoder flowrun used before)."""
    floats = {
        c: np.asarray(getattr(frame, c), dtype=np.float64).tolist() for c in schema.FLOAT_COLUMNS
    }
    msg = schema.VehicleFrameMsg(
        step=frame.step,
        time=frame.time,
        ids=frame.ids,
        types=frame.types,
        edges=frame.edges,
        lanes=np.asarray(frame.lanes).tolist(),
        leader=frame.leader,
        is_rl=np.asarray(frame.is_rl).tolist(),
        roster_version=roster_version,
        **floats,
    )
    return bytes(msg.SerializeToString())


def library_stats_bytes(stats: StepStats) -> bytes:
    msg = schema.StepStatsMsg(**{name: getattr(stats, name) for name in STATS_FIELDS})
    return bytes(msg.SerializeToString())


def empty_frame(step: int = 0, time: float = 0.0) -> VehicleFrame:
    none = np.zeros(0)
    return VehicleFrame(
        step, time, [], [], [], np.zeros(0, dtype=np.int64), none, none, none, none, none,
        none, none, none, none, [], np.zeros(0, dtype=bool),
    )  # fmt: skip


def odd_frame() -> VehicleFrame:
    """Non-finite floats, -1 and large lanes, unicode ids, float32 and strided columns."""
    frame, _ = list(ring_frames(6, 3))[2]
    headway = frame.headway.copy()
    headway[[0, 1, 2]] = [math.inf, -math.inf, math.nan]
    xy = np.stack([frame.x, frame.y], axis=1)  # the kernel's x/y are strided views like these
    return dataclasses.replace(
        frame,
        ids=["véhicule_ü", "车_1", "🚗", "", "a b", "idm_5"],
        leader=["车_1", "🚗", "", "a b", "idm_5", "véhicule_ü"],
        lanes=np.array([-1, 0, 1, 127, 128, 2**31 - 1]),
        headway=headway,
        accel_cmd=np.full(6, math.nan),
        speed=frame.speed.astype(np.float32),
        x=xy[:, 0],
        y=xy[:, 1],
        is_rl=np.array([False, True, False, True, False, False]),
    )


def frames_of(num_vehicles: int, steps: int) -> Iterator[VehicleFrame]:
    for frame, _ in ring_frames(num_vehicles, steps, ring_length=230.0 * num_vehicles / 22):
        yield frame


@pytest.mark.parametrize(
    "frames",
    [
        pytest.param(lambda: frames_of(22, 40), id="22-vehicles-from-step-0"),
        pytest.param(lambda: frames_of(2200, 3), id="2200-vehicles"),
        pytest.param(lambda: [odd_frame()], id="non-finite-negative-lanes-unicode"),
        pytest.param(lambda: [empty_frame(), empty_frame(7, 0.7)], id="no-vehicles"),
        pytest.param(
            lambda: [dataclasses.replace(f, headway=f.headway[:-1]) for f in frames_of(5, 2)],
            id="ragged-columns",
        ),
        pytest.param(
            lambda: [dataclasses.replace(f, step=2**40 + 3, time=1e9) for f in frames_of(3, 2)],
            id="large-step",
        ),
    ],
)
@pytest.mark.parametrize("roster_version", [0, 1, 300])
def test_frame_bytes_equal_the_protobuf_library(frames: object, roster_version: int) -> None:
    encoder = schema.FrameEncoder()
    for frame in frames():  # type: ignore[operator]
        expected = library_frame_bytes(frame, roster_version)
        assert encoder.encode(frame, roster_version) == expected
        assert schema.encode_frame(frame, roster_version) == expected


def test_step_0_at_time_0_leaves_both_fields_out() -> None:
    frame = next(frames_of(2, 1))
    data = schema.encode_frame(frame)
    assert (frame.step, frame.time) == (0, 0.0)
    assert data[:1] == wire.key(3, wire.LEN)  # starts with the first id
    assert schema.parse_frame(data).step == 0


def test_negative_zero_time_is_written_like_upb_does() -> None:
    frame = dataclasses.replace(next(frames_of(2, 1)), time=-0.0)
    data = schema.encode_frame(frame)
    assert math.copysign(1.0, schema.parse_frame(data).time) == -1.0
    # upb (the default backend) writes -0.0, which is not the proto3 default +0.0; the pure
    # Python backend compares with == 0.0 and leaves it out, so compare bytes only with upb.
    if api_implementation.Type() == "upb":
        assert data == library_frame_bytes(frame, 0)


def test_roster_and_column_changes_between_frames_are_encoded() -> None:
    encoder = schema.FrameEncoder()
    frames = list(frames_of(6, 6))
    changed = [
        frames[0],
        dataclasses.replace(frames[1], ids=[*frames[1].ids[:5], "extra"]),  # new roster
        dataclasses.replace(frames[2], ids=list(frames[2].ids), types=list(frames[2].types)),
        dataclasses.replace(frames[3], is_rl=np.ones(6, dtype=bool), lanes=np.arange(6)),
        dataclasses.replace(frames[4], leader=[""] * 6, edges=["x"] * 6),
        frames[5],  # back to the original objects
    ]
    for version, frame in enumerate(changed):
        assert encoder.encode(frame, version) == library_frame_bytes(frame, version)


def test_string_cache_stays_bounded_and_correct_with_endless_new_ids() -> None:
    field_key = wire.key(16, wire.LEN)
    column = wire.StringColumn(field_key, max_cached=10)
    for i in range(100):
        values = [f"flow_{i}.{j}" for j in range(3)] + ["idm_0"]
        assert column.encode(values) == wire.repeated_string(field_key, values)
        assert len(column._cache) < 10 + len(values)


@pytest.mark.parametrize(
    "stats",
    [
        StepStats(0, 0.0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0),
        StepStats(1, 0.1, 22, 5.5, 0.5, 6.0, 1.25, math.nan, 0, 0),
        StepStats(2**33, 1e6, 2200, math.inf, -math.inf, 1.0, 0.0, -3.5, 2, 300),
        StepStats(5, 0.5, 0, math.nan, math.nan, math.nan, math.nan, 0.0, 0, 1),
        StepStats(7, 0.7, 40, 20.0, 1.0, 30.0, 3.0, 0.0, 0, 0, 3, 2, lane_changes=5),
    ],
)
def test_stats_bytes_equal_the_protobuf_library(stats: StepStats) -> None:
    assert schema.encode_stats(stats) == library_stats_bytes(stats)


def test_lane_changes_survive_a_round_trip() -> None:
    stats = StepStats(7, 0.7, 40, 20.0, 1.0, 30.0, 3.0, 0.0, 0, 0, 3, 2, lane_changes=5)
    assert schema.decode_stats(schema.encode_stats(stats)).lane_changes == 5


def test_stats_of_a_run_equal_the_protobuf_library() -> None:
    for frame, stats in ring_frames(22, 50):
        for s in (stats, step_stats(frame, reward=0.0, collisions=1)):
            assert schema.encode_stats(s) == library_stats_bytes(s)


@pytest.mark.parametrize(
    "value", [1, 0x7F, 0x80, 0x3FFF, 0x4000, 0x1FFFFF, 2**32, 2**63, 2**64 - 1]
)
def test_varint_matches_a_uint64_field(value: int) -> None:
    assert wire.key(1, wire.VARINT) + wire.varint(value) == library_stats_bytes(
        StepStats(value, 0.0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0)
    )


def test_negative_int32_is_ten_bytes_and_out_of_range_values_fail() -> None:
    assert wire.varint(0) == b"\x00"  # (a zero scalar field itself is left out, see above)
    assert wire.varint(-1) == b"\xff" * 9 + b"\x01"
    assert wire.packed_int32(b"\x32", [-(2**31)]) == b"\x32\x0a" + wire.varint(-(2**31))
    with pytest.raises(ValueError):
        wire.packed_int32(b"\x32", [2**31])
    with pytest.raises(ValueError):
        wire.varint(2**64)


def test_decoding_the_hand_written_bytes_gives_the_frame_back() -> None:
    frame = odd_frame()
    back = schema.frame_from_message(schema.parse_frame(schema.encode_frame(frame)))
    for f in dataclasses.fields(VehicleFrame):
        a, b = getattr(frame, f.name), getattr(back, f.name)
        if isinstance(a, np.ndarray):
            np.testing.assert_array_equal(b, a.astype(b.dtype), err_msg=f.name)
        else:
            assert b == a, f.name
