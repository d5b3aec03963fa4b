"""Flow compatibility: re-exports.

Flow's ``flow.controllers.car_following_models`` import path (flowrun's classes).
"""

from flowrun.controllers.car_following import (
    BandoFTLController,
    BCMController,
    CFMController,
    GippsController,
    IDMController,
    LACController,
    LinearOVM,
    OVMController,
)
from flowrun.controllers.rl import SimCarFollowingController

__all__ = [
    "BCMController",
    "BandoFTLController",
    "CFMController",
    "GippsController",
    "IDMController",
    "LACController",
    "LinearOVM",
    "OVMController",
    "SimCarFollowingController",
]
