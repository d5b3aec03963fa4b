"""Protobuf schemas of the flowrun topics, built in Python (no ``protoc`` step).

Why protobuf: packed doubles keep ``inf``/``nan`` exactly, Foxglove decodes the messages,
and decoding a 2,200-vehicle frame back to numpy arrays takes ~0.5 ms. JSON needed ~120 µs
per 22-vehicle frame with the standard library and ~3x the bytes.

Writing builds no message objects: :class:`FrameEncoder` and :func:`encode_stats` write the
wire format directly (:mod:`flowrun.recording.wire`), byte for byte what the protobuf
library's ``SerializeToString`` writes (``tests/test_recording_wire.py``). Measured with
``bench/record_write.py``: ~3-4 µs per 22-vehicle frame (the library: ~16-21 µs) and ~32 µs
per 2,200-vehicle frame (~1.0-1.3 ms); a step's stats take ~1 µs. Reading uses the library's
message classes (:func:`parse_frame`, :func:`decode_stats`).

Foxglove decodes these messages from the schema record alone: schema encoding ``protobuf``,
schema data = a serialised ``FileDescriptorSet``, schema name = the fully-qualified type name.
"""

from __future__ import annotations

import math
import struct
from typing import Any

import numpy as np
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from flowrun.recording import wire
from flowrun.recording.frames import StepStats, VehicleFrame

VEHICLES_TOPIC = "/flowrun/vehicles"
STATS_TOPIC = "/flowrun/stats"
VEHICLES_TYPE = "flowrun.VehicleFrame"
STATS_TYPE = "flowrun.StepStats"
#: Written only on networks with traffic lights (encoded by :mod:`flowrun.recording.signals`).
SIGNALS_TOPIC = "/flowrun/traffic_lights"
SIGNALS_TYPE = "flowrun.SignalFrame"
ENCODING = "protobuf"

_F = descriptor_pb2.FieldDescriptorProto
_STRING_COLUMNS = ("ids", "types", "edges", "leader")
FLOAT_COLUMNS = (
    "lane_pos",
    "position",
    "odometer",
    "x",
    "y",
    "speed",
    "accel_cmd",
    "accel_real",
    "headway",
)

# (name, type, repeated) in field-number order; the numbers are part of the file format.
_VEHICLE_FIELDS: tuple[tuple[str, int, bool], ...] = (
    ("step", _F.TYPE_UINT64, False),
    ("time", _F.TYPE_DOUBLE, False),
    ("ids", _F.TYPE_STRING, True),
    ("types", _F.TYPE_STRING, True),
    ("edges", _F.TYPE_STRING, True),
    ("lanes", _F.TYPE_INT32, True),
    ("lane_pos", _F.TYPE_DOUBLE, True),
    ("position", _F.TYPE_DOUBLE, True),
    ("odometer", _F.TYPE_DOUBLE, True),
    ("x", _F.TYPE_DOUBLE, True),
    ("y", _F.TYPE_DOUBLE, True),
    ("speed", _F.TYPE_DOUBLE, True),
    ("accel_cmd", _F.TYPE_DOUBLE, True),
    ("accel_real", _F.TYPE_DOUBLE, True),
    ("headway", _F.TYPE_DOUBLE, True),
    ("leader", _F.TYPE_STRING, True),
    ("is_rl", _F.TYPE_BOOL, True),
    ("roster_version", _F.TYPE_UINT32, False),
)
_STATS_FIELDS: tuple[tuple[str, int, bool], ...] = (
    ("step", _F.TYPE_UINT64, False),
    ("time", _F.TYPE_DOUBLE, False),
    ("num_vehicles", _F.TYPE_UINT32, False),
    ("mean_speed", _F.TYPE_DOUBLE, False),
    ("min_speed", _F.TYPE_DOUBLE, False),
    ("max_speed", _F.TYPE_DOUBLE, False),
    ("speed_std", _F.TYPE_DOUBLE, False),
    ("reward", _F.TYPE_DOUBLE, False),
    ("collisions", _F.TYPE_UINT32, False),
    ("teleports", _F.TYPE_UINT32, False),
    # Added for open networks; older logs leave them out and read back as 0.
    ("departed", _F.TYPE_UINT32, False),
    ("arrived", _F.TYPE_UINT32, False),
    # Added for lane changes on open roads; older logs read back as 0.
    ("lane_changes", _F.TYPE_UINT32, False),
)
SIGNAL_FIELDS: tuple[tuple[str, int, bool], ...] = (
    ("step", _F.TYPE_UINT64, False),
    ("time", _F.TYPE_DOUBLE, False),
    ("ids", _F.TYPE_STRING, True),
    ("states", _F.TYPE_STRING, True),
    ("phases", _F.TYPE_INT32, True),
    ("programs", _F.TYPE_STRING, True),
)


def _file_descriptor() -> descriptor_pb2.FileDescriptorProto:
    fdp = descriptor_pb2.FileDescriptorProto(
        name="flowrun/recording.proto", package="flowrun", syntax="proto3"
    )
    messages = (
        ("VehicleFrame", _VEHICLE_FIELDS),
        ("StepStats", _STATS_FIELDS),
        ("SignalFrame", SIGNAL_FIELDS),  # added with traffic lights; older logs lack it
    )
    for msg_name, fields in messages:
        msg = fdp.message_type.add(name=msg_name)
        for number, (name, ftype, repeated) in enumerate(fields, start=1):
            label = _F.LABEL_REPEATED if repeated else _F.LABEL_OPTIONAL
            msg.field.add(name=name, number=number, type=ftype, label=label, json_name=name)
    return fdp


_FDP = _file_descriptor()
_POOL = descriptor_pool.DescriptorPool()
_POOL.Add(_FDP)
VehicleFrameMsg: Any = message_factory.GetMessageClass(_POOL.FindMessageTypeByName(VEHICLES_TYPE))
StepStatsMsg: Any = message_factory.GetMessageClass(_POOL.FindMessageTypeByName(STATS_TYPE))
SignalFrameMsg: Any = message_factory.GetMessageClass(_POOL.FindMessageTypeByName(SIGNALS_TYPE))


def schema_data() -> bytes:
    """The serialised ``FileDescriptorSet`` stored in every schema record."""
    return descriptor_pb2.FileDescriptorSet(file=[_FDP]).SerializeToString()


def field_keys(fields: tuple[tuple[str, int, bool], ...]) -> dict[str, bytes]:
    """Encoded key of every field: packed/repeated fields are length-delimited records,
    doubles fixed 64-bit, the other scalars varints."""
    keys = {}
    for number, (name, ftype, repeated) in enumerate(fields, start=1):
        wire_type = (
            wire.LEN if repeated else wire.FIXED64 if ftype == _F.TYPE_DOUBLE else wire.VARINT
        )
        keys[name] = wire.key(number, wire_type)
    return keys


_VK = field_keys(_VEHICLE_FIELDS)
_SK = field_keys(_STATS_FIELDS)
_FLOAT_KEYS = tuple(_VK[name] for name in FLOAT_COLUMNS)
# Keys used on every step. Both messages have step = 1 and time = 2; field numbers below 16
# make one-byte keys.
_STEP_KEY, _TIME_KEY, _ROSTER_KEY = _VK["step"], _VK["time"][0], _VK["roster_version"]
_NUM_VEHICLES_KEY, _COLLISIONS_KEY = _SK["num_vehicles"], _SK["collisions"]
_TELEPORTS_KEY, _DEPARTED_KEY, _ARRIVED_KEY = _SK["teleports"], _SK["departed"], _SK["arrived"]
_LANE_CHANGES_KEY = _SK["lane_changes"]
_KEYED_DOUBLE = struct.Struct("<Bd").pack
_STATS_DOUBLES = struct.Struct("<" + "Bd" * 5).pack  # mean/min/max/std speed, reward
_STATS_DOUBLE_KEYS = tuple(
    _SK[name][0] for name in ("mean_speed", "min_speed", "max_speed", "speed_std", "reward")
)
_ascontiguous = np.ascontiguousarray
_copysign = math.copysign


class FrameEncoder:
    """Writes ``flowrun.VehicleFrame`` messages straight to the protobuf wire format.

    The bytes equal ``VehicleFrameMsg(...).SerializeToString()`` of the same values (fields
    in number order, proto3 zero scalars and empty repeated fields left out), at a fraction
    of the cost: the float columns are copied from the numpy arrays as they are, and columns
    that repeat from step to step are encoded once. The kernel hands over the same
    ``ids``/``types``/``is_rl`` objects while the roster holds, and a leader list that is
    reused while the order holds, so most steps cost an identity check for those; edge and
    leader names are cached per string. Frames are treated as read-only: a list or array
    changed in place and passed again keeps its previous encoding.

    One encoder per output stream: the caches only pay when consecutive frames are alike.
    """

    def __init__(self) -> None:
        self._ids = wire.StringColumn(_VK["ids"])
        self._types = wire.StringColumn(_VK["types"])
        self._edges = wire.StringColumn(_VK["edges"])
        self._leader = wire.StringColumn(_VK["leader"])
        lanes_key, rl_key = _VK["lanes"], _VK["is_rl"]
        self._lanes = wire.ArrayColumn(lambda a: wire.packed_int32(lanes_key, a))
        self._is_rl = wire.ArrayColumn(lambda a: wire.packed_bool(rl_key, a))
        self._heads: dict[int, tuple[bytes, ...]] = {}  # column bytes -> key + length, per column

    def encode(self, frame: VehicleFrame, roster_version: int = 0) -> bytes:
        """Serialise ``frame`` (see :func:`encode_frame`)."""
        step, t = frame.step, frame.time
        parts: list[Any] = [
            _STEP_KEY + wire.varint(step) if step else b"",
            # proto3 leaves out +0.0 only (upb writes -0.0)
            _KEYED_DOUBLE(_TIME_KEY, t) if t or _copysign(1.0, t) < 0.0 else b"",
            self._ids.encode(frame.ids),
            self._types.encode(frame.types),
            self._edges.encode(frame.edges),
            self._lanes.encode(frame.lanes),
        ]
        # The float columns, spelled out: a loop over them costs twice as much (2.4 µs at 22
        # vehicles vs 1.1 µs). bytes.join copies straight from the arrays' buffers.
        f8, a = wire.F8, _ascontiguous
        c0 = a(frame.lane_pos, f8)
        c1 = a(frame.position, f8)
        c2 = a(frame.odometer, f8)
        c3 = a(frame.x, f8)
        c4 = a(frame.y, f8)
        c5 = a(frame.speed, f8)
        c6 = a(frame.accel_cmd, f8)
        c7 = a(frame.accel_real, f8)
        c8 = a(frame.headway, f8)
        size = c0.nbytes
        same = size == c1.nbytes == c2.nbytes == c3.nbytes == c4.nbytes == c5.nbytes
        if size and same and size == c6.nbytes == c7.nbytes == c8.nbytes:
            heads = self._heads.get(size) or self._float_heads(size)
            h0, h1, h2, h3, h4, h5, h6, h7, h8 = heads
            parts += (h0, c0, h1, c1, h2, c2, h3, c3, h4, c4, h5, c5, h6, c6, h7, c7, h8, c8)
        else:  # no vehicles (fields left out), or columns of different lengths
            for field_key, arr in zip(
                _FLOAT_KEYS, (c0, c1, c2, c3, c4, c5, c6, c7, c8), strict=True
            ):
                if arr.nbytes:
                    parts += (field_key, wire.varint(arr.nbytes), arr)
        parts += (
            self._leader.encode(frame.leader),
            self._is_rl.encode(frame.is_rl),
            _ROSTER_KEY + wire.varint(roster_version) if roster_version else b"",
        )
        return b"".join(parts)

    def _float_heads(self, size: int) -> tuple[bytes, ...]:
        if len(self._heads) > 1024:  # many different vehicle counts: start over
            self._heads.clear()
        heads = self._heads[size] = tuple(key + wire.varint(size) for key in _FLOAT_KEYS)
        return heads


_ENCODER = FrameEncoder()


def encode_frame(frame: VehicleFrame, roster_version: int = 0) -> bytes:
    """Serialise a :class:`VehicleFrame` (non-finite floats are kept as they are).

    Uses a module-wide :class:`FrameEncoder`; a writer of its own stream should own one.

    Args:
        frame: the step to encode.
        roster_version: changes whenever ``ids``/``types``/``is_rl`` change, so readers can
            skip re-reading those columns (0 = unknown).
    """
    return _ENCODER.encode(frame, roster_version)


def _double(field_key: int, value: float) -> bytes:
    if value or _copysign(1.0, value) < 0.0:
        return _KEYED_DOUBLE(field_key, value)
    return b""


def encode_stats(stats: StepStats) -> bytes:
    """Serialise a :class:`StepStats` (same bytes as the protobuf library's)."""
    s = stats
    step, t, n, collisions, teleports = s.step, s.time, s.num_vehicles, s.collisions, s.teleports
    doubles = (s.mean_speed, s.min_speed, s.max_speed, s.speed_std, s.reward)
    if 0.0 in doubles:  # rare: some are +-0.0, write them one by one
        tail = b"".join(map(_double, _STATS_DOUBLE_KEYS, doubles))
    else:  # one pack for all five
        k1, k2, k3, k4, k5 = _STATS_DOUBLE_KEYS
        mean, low, high, std, reward = doubles
        tail = _STATS_DOUBLES(k1, mean, k2, low, k3, high, k4, std, k5, reward)
    return b"".join(
        (
            _STEP_KEY + wire.varint(step) if step else b"",
            _KEYED_DOUBLE(_TIME_KEY, t) if t or _copysign(1.0, t) < 0.0 else b"",
            _NUM_VEHICLES_KEY + wire.varint(n) if n else b"",
            tail,
            _COLLISIONS_KEY + wire.varint(collisions) if collisions else b"",
            _TELEPORTS_KEY + wire.varint(teleports) if teleports else b"",
            _DEPARTED_KEY + wire.varint(s.departed) if s.departed else b"",
            _ARRIVED_KEY + wire.varint(s.arrived) if s.arrived else b"",
            _LANE_CHANGES_KEY + wire.varint(s.lane_changes) if s.lane_changes else b"",
        )
    )


def parse_frame(data: bytes) -> Any:
    """Parse ``/flowrun/vehicles`` bytes into the raw protobuf message (fast column access)."""
    return VehicleFrameMsg.FromString(data)


def frame_from_message(msg: Any, keep: list[int] | None = None) -> VehicleFrame:
    """Build a :class:`VehicleFrame` from a parsed message, optionally keeping some vehicles.

    Args:
        msg: a parsed ``flowrun.VehicleFrame`` message.
        keep: indices of the vehicles to keep (``None`` keeps all).
    """

    def floats(name: str) -> Any:
        arr = np.array(getattr(msg, name), dtype=np.float64)
        return arr if keep is None else arr[keep]

    def strings(name: str) -> list[str]:
        values = list(getattr(msg, name))
        return values if keep is None else [values[i] for i in keep]

    lanes = np.array(msg.lanes, dtype=np.int64)
    is_rl = np.array(msg.is_rl, dtype=np.bool_)
    if keep is not None:
        lanes, is_rl = lanes[keep], is_rl[keep]
    return VehicleFrame(
        step=int(msg.step),
        time=float(msg.time),
        ids=strings("ids"),
        types=strings("types"),
        edges=strings("edges"),
        lanes=lanes,
        lane_pos=floats("lane_pos"),
        position=floats("position"),
        odometer=floats("odometer"),
        x=floats("x"),
        y=floats("y"),
        speed=floats("speed"),
        accel_cmd=floats("accel_cmd"),
        accel_real=floats("accel_real"),
        headway=floats("headway"),
        leader=strings("leader"),
        is_rl=is_rl,
    )


def decode_stats(data: bytes) -> StepStats:
    """Parse ``/flowrun/stats`` bytes into a :class:`StepStats` (``departed``/``arrived`` are 0
    in logs written before they existed: proto3 reads a missing field as zero)."""
    msg = StepStatsMsg.FromString(data)
    return StepStats(
        step=int(msg.step),
        time=float(msg.time),
        num_vehicles=int(msg.num_vehicles),
        mean_speed=float(msg.mean_speed),
        min_speed=float(msg.min_speed),
        max_speed=float(msg.max_speed),
        speed_std=float(msg.speed_std),
        reward=float(msg.reward),
        collisions=int(msg.collisions),
        teleports=int(msg.teleports),
        departed=int(msg.departed),
        arrived=int(msg.arrived),
        lane_changes=int(msg.lane_changes),
    )
