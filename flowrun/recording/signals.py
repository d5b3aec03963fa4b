"""``/flowrun/traffic_lights``: every signal's state per logged step (``flowrun.SignalFrame``).

Written like the vehicle frames: straight to the protobuf wire format (the same bytes as the
protobuf library's ``SerializeToString``, ``tests/test_recording_signals.py``), read back
through the library's message class. The ids and programs rarely change from step to step,
so their encoding is reused while they hold.
"""

from __future__ import annotations

import math
import struct

import numpy as np

from flowrun.recording import wire
from flowrun.recording.frames import SignalFrame
from flowrun.recording.schema import SIGNAL_FIELDS, SignalFrameMsg, field_keys

_K = field_keys(SIGNAL_FIELDS)
_STEP_KEY, _TIME_KEY = _K["step"], _K["time"]
_DOUBLE = struct.Struct("<d").pack


class SignalEncoder:
    """Serialises :class:`SignalFrame` messages (one encoder per output stream)."""

    def __init__(self) -> None:
        self._ids = wire.StringColumn(_K["ids"])
        self._states = wire.StringColumn(_K["states"])
        self._programs = wire.StringColumn(_K["programs"])

    def encode(self, frame: SignalFrame) -> bytes:
        """The message bytes of ``frame``."""
        t = frame.time
        return b"".join(
            (
                _STEP_KEY + wire.varint(frame.step) if frame.step else b"",
                _TIME_KEY + _DOUBLE(t) if t or math.copysign(1.0, t) < 0.0 else b"",
                self._ids.encode(frame.ids),
                self._states.encode(frame.states),
                wire.packed_int32(_K["phases"], frame.phases),
                self._programs.encode(frame.programs),
            )
        )


def decode_signals(data: bytes) -> SignalFrame:
    """Parse ``/flowrun/traffic_lights`` bytes into a :class:`SignalFrame`."""
    msg = SignalFrameMsg.FromString(data)
    return SignalFrame(
        step=int(msg.step),
        time=float(msg.time),
        ids=list(msg.ids),
        states=list(msg.states),
        phases=np.array(msg.phases, dtype=np.int64),
        programs=list(msg.programs),
    )
