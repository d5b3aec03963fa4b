"""MCAP recording of per-step vehicle states: writer, CRC-checking reader (salvage around
damage, with a report of what was lost) and repair."""

from flowrun.recording.damage import DamageReport, Loss
from flowrun.recording.frames import SignalFrame, StepStats, VehicleFrame
from flowrun.recording.reader import McapLog, open_log
from flowrun.recording.repair import RepairReport, repair
from flowrun.recording.schema import SIGNALS_TOPIC, STATS_TOPIC, VEHICLES_TOPIC
from flowrun.recording.writer import METADATA_NAME, McapRecorder

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
