"""The ``/flowrun/scene`` topic: ``foxglove.SceneUpdate`` messages for Foxglove's 3D panel.

The schema record holds Foxglove's own protobuf definitions (from the
``foxglove-schemas-protobuf`` package: ``foxglove/SceneUpdate.proto`` and what it imports, as
a ``FileDescriptorSet``). The first message carries the road (entity ``road``: one line strip
per lane, as wide as the lane), every message the cars (entity ``cars``: one cube per car,
coloured by speed, AVs with a blue block on the roof) and, on networks with lights, the signal
heads (entity ``lights``: one sphere per link in its state's colour), plus the colour legend
(entity ``legend``: a text). Coordinates are the network's, in frame ``map``, z up.

Cubes and spheres are written straight to the wire format, all cars of a step in a few numpy
operations (every field written, so every car's record has the same layout).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from flowrun.recording import wire
from flowrun.recording.frames import SignalFrame, VehicleFrame
from flowrun.render import Road, speed_top
from flowrun.render.colours import AV_COLOUR, SIGNAL_OFF, SPEED_STOPS, signal_colour
from flowrun.types import FloatArray

SCENE_TOPIC = "/flowrun/scene"
SCENE_TYPE = "foxglove.SceneUpdate"
FRAME_ID = "map"
CAR_LENGTH, CAR_WIDTH, CAR_HEIGHT = 5.0, 1.8, 1.5
ROAD_RGBA = (0.47, 0.47, 0.47, 1.0)

_ENTITIES = wire.key(2, wire.LEN)  # SceneUpdate.entities
_CUBES, _SPHERES = 8, 9  # SceneEntity.cubes, .spheres


def schema_data() -> bytes:
    """Foxglove's ``SceneUpdate`` schema: a ``FileDescriptorSet`` of its .proto and imports."""
    from foxglove_schemas_protobuf import SceneUpdate_pb2
    from google.protobuf import descriptor_pb2

    files: list[Any] = []
    seen: set[str] = set()

    def add(fd: Any) -> None:
        if fd.name in seen:
            return
        seen.add(fd.name)
        for dep in fd.dependencies:
            add(dep)
        proto = descriptor_pb2.FileDescriptorProto()
        fd.CopyToProto(proto)
        files.append(proto)

    add(SceneUpdate_pb2.DESCRIPTOR)
    return descriptor_pb2.FileDescriptorSet(file=files).SerializeToString()


def _layout(field: int) -> tuple[np.dtype[Any], bytes]:
    """Record layout of one cube/sphere (pose, size, colour; every double present) inside a
    ``SceneEntity`` field ``field``: a structured dtype over its bytes, and the constant bytes.
    """
    names: list[str] = []
    offsets: list[int] = []
    out = bytearray()

    def doubles(number: int, fields: Sequence[str]) -> None:
        out.extend(wire.key(number, wire.LEN) + wire.varint(9 * len(fields)))
        for i, name in enumerate(fields, start=1):
            out.extend(wire.key(i, wire.FIXED64))
            names.append(name)
            offsets.append(len(out))
            out.extend(bytes(8))

    pose_len = 2 + 27 + 2 + 36  # position (3 doubles) and orientation (4)
    body_len = 2 + pose_len + 2 + 27 + 2 + 36  # pose, size (3), colour (4)
    out.extend(wire.key(field, wire.LEN) + wire.varint(body_len))
    out.extend(wire.key(1, wire.LEN) + wire.varint(pose_len))
    doubles(1, ("x", "y", "z"))
    doubles(2, ("qx", "qy", "qz", "qw"))
    doubles(2, ("sx", "sy", "sz"))
    doubles(3, ("r", "g", "b", "a"))
    spec: Any = {"names": names, "formats": ["<f8"] * len(names), "offsets": offsets,
                 "itemsize": len(out)}  # fmt: skip
    dtype: np.dtype[Any] = np.dtype(spec)
    return dtype, bytes(out)


_CUBE = _layout(_CUBES)
_SPHERE = _layout(_SPHERES)


def _boxes(layout: tuple[np.dtype[Any], bytes], xyz: FloatArray, yaw: FloatArray,
           size: FloatArray, rgba: FloatArray) -> bytes:  # fmt: skip
    """Cubes or spheres: centres ``(n, 3)``, yaw (radians about z), sizes ``(n, 3)``, colours
    ``(n, 4)`` in 0-1, as consecutive ``SceneEntity`` field records."""
    dtype, template = layout
    n = len(xyz)
    buf = np.frombuffer(template * n, dtype=np.uint8).copy()  # keys and lengths included
    rec = buf.view(dtype)
    rec["x"], rec["y"], rec["z"] = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    rec["qx"] = rec["qy"] = 0.0
    rec["qz"], rec["qw"] = np.sin(yaw / 2), np.cos(yaw / 2)
    rec["sx"], rec["sy"], rec["sz"] = size[:, 0], size[:, 1], size[:, 2]
    rec["r"], rec["g"], rec["b"], rec["a"] = rgba[:, 0], rgba[:, 1], rgba[:, 2], rgba[:, 3]
    return buf.tobytes()


def _entity(time_ns: int, entity_id: str, body: bytes) -> bytes:
    sec, nsec = divmod(time_ns, 1_000_000_000)
    stamp = (b"\x08" + wire.varint(sec) if sec else b"") + (
        b"\x10" + wire.varint(nsec) if nsec else b""
    )
    data = b"".join((
        wire.length_delimited(b"\x0a", stamp),
        wire.string_record(b"\x12", FRAME_ID),
        wire.string_record(b"\x1a", entity_id),
        body,
    ))  # fmt: skip
    return _ENTITIES + wire.varint(len(data)) + data


def _speed_rgba(speed: FloatArray, top: float) -> FloatArray:
    f = np.clip(np.nan_to_num(speed / top), 0.0, 1.0) * (len(SPEED_STOPS) - 1)
    i = np.minimum(f.astype(np.int64), len(SPEED_STOPS) - 2)
    w = (f - i)[:, None]
    rgb = (SPEED_STOPS[i] * (1 - w) + SPEED_STOPS[i + 1] * w) / 255
    return np.concatenate([rgb, np.ones((len(speed), 1))], axis=1)


def _message(name: str) -> Any:
    """A message class of Foxglove's schemas (``foxglove-schemas-protobuf``)."""
    import importlib

    return getattr(importlib.import_module(f"foxglove_schemas_protobuf.{name}_pb2"), name)


class SceneEncoder:
    """Encodes each logged step as one ``foxglove.SceneUpdate`` (see the module docstring).

    Args:
        road: the network's road (``None``: no road entity; cars and lights only).
        lengths: car length per vehicle type, m (default 5 m).
        top: top of the speed colour scale, m/s (``None``: the fastest car so far, rounded up
            by :func:`~flowrun.render.speed_top`; the legend entity says the scale in use).
    """

    def __init__(
        self, road: Road | None, lengths: dict[str, float] | None = None, top: float | None = None
    ) -> None:
        self.road = road
        self.lengths = dict(lengths or {})
        self.top = top
        self.fastest = 0.0
        self._road_sent = False
        self._legend_top: float | None = None
        heads = road.signals if road is not None else []
        self._heads = np.array([(h.x, h.y, 0.6) for h in heads], dtype=np.float64).reshape(-1, 3)

    def encode(self, frame: VehicleFrame, signals: SignalFrame | None, time_ns: int) -> bytes:
        """The ``SceneUpdate`` bytes of one step at log time ``time_ns``."""
        parts = []
        if not self._road_sent and self.road is not None:
            parts.append(self._road_entity(time_ns))
            self._road_sent = True
        speed = np.nan_to_num(np.asarray(frame.speed, dtype=np.float64))
        if speed.size:
            self.fastest = max(self.fastest, float(speed.max()))
        top = self.top if self.top is not None else speed_top(self.fastest)
        if top != self._legend_top:
            parts.append(self._legend(time_ns, top))
            self._legend_top = top
        parts.append(_entity(time_ns, "cars", self._cars(frame, speed, top)))
        if signals is not None and len(self._heads):
            parts.append(_entity(time_ns, "lights", self._lights(signals)))
        return b"".join(parts)

    def _cars(self, frame: VehicleFrame, speed: FloatArray, top: float) -> bytes:
        n = len(frame.ids)
        if not n:
            return b""
        x = np.asarray(frame.x, dtype=np.float64)
        y = np.asarray(frame.y, dtype=np.float64)
        yaw = np.zeros(n)
        if self.road is not None and len(frame.edges) == n:
            yaw = np.nan_to_num(
                self.road.headings(frame.edges, np.asarray(frame.lanes), frame.lane_pos, x, y)
            )
        length = np.array([self.lengths.get(t, CAR_LENGTH) for t in frame.types])
        z = np.full(n, CAR_HEIGHT / 2)
        centre = np.stack([x - np.cos(yaw) * length / 2, y - np.sin(yaw) * length / 2, z], axis=1)
        size = np.stack([length, np.full(n, CAR_WIDTH), np.full(n, CAR_HEIGHT)], axis=1)
        body = _boxes(_CUBE, centre, yaw, size, _speed_rgba(speed, top))
        rl = np.asarray(frame.is_rl, dtype=bool)
        if rl.any():
            k = int(rl.sum())
            roof = centre[rl] + np.array([0.0, 0.0, CAR_HEIGHT / 2 + 0.3])
            rgba = np.tile([*(c / 255 for c in AV_COLOUR), 1.0], (k, 1))
            body += _boxes(_CUBE, roof, yaw[rl], np.tile([2.0, 1.4, 0.6], (k, 1)), rgba)
        return body

    def _lights(self, signals: SignalFrame) -> bytes:
        assert self.road is not None
        states = dict(zip(signals.ids, signals.states, strict=False))
        rgba = []
        for head in self.road.signals:
            state = states.get(head.light, "")
            rgb = signal_colour(state[head.link]) if head.link < len(state) else SIGNAL_OFF
            rgba.append((rgb[0] / 255, rgb[1] / 255, rgb[2] / 255, 1.0))
        n = len(self._heads)
        return _boxes(_SPHERE, self._heads, np.zeros(n), np.full((n, 3), 1.2), np.array(rgba))

    def _road_entity(self, time_ns: int) -> bytes:
        assert self.road is not None
        line, point, colour, pose = (
            _message("LinePrimitive"), _message("Point3"), _message("Color"), _message("Pose")
        )  # fmt: skip
        grey = colour(r=ROAD_RGBA[0], g=ROAD_RGBA[1], b=ROAD_RGBA[2], a=ROAD_RGBA[3])
        lines = [
            line(
                type=line.LINE_STRIP,
                pose=pose(orientation={"w": 1.0}),
                thickness=lane.width,
                points=[point(x=float(px), y=float(py), z=0.0) for px, py in lane.shape],
                color=grey,
            )
            for lane in self.road.lanes
        ]
        body = b"".join(
            wire.length_delimited(wire.key(11, wire.LEN), ln.SerializeToString()) for ln in lines
        )
        return _entity(time_ns, "road", body)

    def _legend(self, time_ns: int, top: float) -> bytes:
        text, pose, colour = _message("TextPrimitive"), _message("Pose"), _message("Color")
        xmin, _, _, ymax = self.road.bounds if self.road is not None else (0.0, 0.0, 0.0, 0.0)
        label = text(
            pose=pose(position={"x": xmin, "y": ymax + 5.0, "z": 2.0}, orientation={"w": 1.0}),
            billboard=True,
            font_size=14.0,
            scale_invariant=True,
            color=colour(r=0.1, g=0.1, b=0.1, a=1.0),
            text=f"speed: red 0 m/s - green {top:g} m/s; blue roof: AV",
        )
        body = wire.length_delimited(wire.key(13, wire.LEN), label.SerializeToString())
        return _entity(time_ns, "legend", body)
