"""MCAP recording of per-step vehicle states: writer, CRC-checking reader (salvage around
damage, with a report of what was lost) and repair.

The names below are imported from their modules when first used, so importing
``flowrun.recording.frames`` (the step records an environment fills) does not load the MCAP
and protobuf libraries: ``flowrun validate`` and ``flowrun list`` start faster.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from flowrun.recording.damage import DamageReport, Loss
    from flowrun.recording.frames import SignalFrame, StepStats, VehicleFrame
    from flowrun.recording.reader import McapLog, open_log
    from flowrun.recording.repair import RepairReport, repair
    from flowrun.recording.schema import SIGNALS_TOPIC, STATS_TOPIC, VEHICLES_TOPIC
    from flowrun.recording.writer import METADATA_NAME, McapRecorder

#: Each public name -> the module that defines it.
_WHERE = {
    "DamageReport": "damage",
    "Loss": "damage",
    "SignalFrame": "frames",
    "StepStats": "frames",
    "VehicleFrame": "frames",
    "McapLog": "reader",
    "open_log": "reader",
    "RepairReport": "repair",
    "repair": "repair",
    "SIGNALS_TOPIC": "schema",
    "STATS_TOPIC": "schema",
    "VEHICLES_TOPIC": "schema",
    "METADATA_NAME": "writer",
    "McapRecorder": "writer",
}

__all__ = [
    "METADATA_NAME",
    "SIGNALS_TOPIC",
    "STATS_TOPIC",
    "VEHICLES_TOPIC",
    "DamageReport",
    "Loss",
    "McapLog",
    "McapRecorder",
    "RepairReport",
    "SignalFrame",
    "StepStats",
    "VehicleFrame",
    "open_log",
    "repair",
]


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value
