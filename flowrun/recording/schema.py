"""Protobuf schemas of the two flowrun topics, built in Python (no ``protoc`` step).

Why protobuf: measured with ``bench/record_write.py``, building and serialising one
22-vehicle frame costs ~15-25 µs (2,200 vehicles: ~1.5 ms), packed doubles keep ``inf``/``nan``
exactly, and decoding a 2,200-vehicle frame back to numpy arrays takes ~0.5 ms. JSON needed
~120 µs per 22-vehicle frame with the standard library and ~3x the bytes.

Foxglove decodes these messages from the schema record alone: schema encoding ``protobuf``,
schema data = a serialised ``FileDescriptorSet``, schema name = the fully-qualified type name.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from flowrun.recording.frames import StepStats, VehicleFrame

VEHICLES_TOPIC = "/flowrun/vehicles"
STATS_TOPIC = "/flowrun/stats"
VEHICLES_TYPE = "flowrun.VehicleFrame"
STATS_TYPE = "flowrun.StepStats"
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
)


def _file_descriptor() -> descriptor_pb2.FileDescriptorProto:
    fdp = descriptor_pb2.FileDescriptorProto(
        name="flowrun/recording.proto", package="flowrun", syntax="proto3"
    )
    for msg_name, fields in (("VehicleFrame", _VEHICLE_FIELDS), ("StepStats", _STATS_FIELDS)):
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


def schema_data() -> bytes:
    """The serialised ``FileDescriptorSet`` stored in both schema records."""
    return descriptor_pb2.FileDescriptorSet(file=[_FDP]).SerializeToString()


def encode_frame(frame: VehicleFrame, roster_version: int = 0) -> bytes:
    """Serialise a :class:`VehicleFrame` (non-finite floats are kept as they are).

    Args:
        frame: the step to encode.
        roster_version: changes whenever ``ids``/``types``/``is_rl`` change, so readers can
            skip re-reading those columns (0 = unknown).
    """
    return bytes(
        VehicleFrameMsg(
            step=frame.step,
            time=frame.time,
            ids=frame.ids,
            types=frame.types,
            edges=frame.edges,
            lanes=np.asarray(frame.lanes).tolist(),
            lane_pos=np.asarray(frame.lane_pos, dtype=np.float64).tolist(),
            position=np.asarray(frame.position, dtype=np.float64).tolist(),
            odometer=np.asarray(frame.odometer, dtype=np.float64).tolist(),
            x=np.asarray(frame.x, dtype=np.float64).tolist(),
            y=np.asarray(frame.y, dtype=np.float64).tolist(),
            speed=np.asarray(frame.speed, dtype=np.float64).tolist(),
            accel_cmd=np.asarray(frame.accel_cmd, dtype=np.float64).tolist(),
            accel_real=np.asarray(frame.accel_real, dtype=np.float64).tolist(),
            headway=np.asarray(frame.headway, dtype=np.float64).tolist(),
            leader=frame.leader,
            is_rl=np.asarray(frame.is_rl).tolist(),
            roster_version=roster_version,
        ).SerializeToString()
    )


def encode_stats(stats: StepStats) -> bytes:
    """Serialise a :class:`StepStats`."""
    return bytes(
        StepStatsMsg(
            step=stats.step,
            time=stats.time,
            num_vehicles=stats.num_vehicles,
            mean_speed=stats.mean_speed,
            min_speed=stats.min_speed,
            max_speed=stats.max_speed,
            speed_std=stats.speed_std,
            reward=stats.reward,
            collisions=stats.collisions,
            teleports=stats.teleports,
        ).SerializeToString()
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
    """Parse ``/flowrun/stats`` bytes into a :class:`StepStats`."""
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
    )
