"""Controllers: pure, vectorised formulas that turn vehicle state into commands.

Flow-compatible names: ``from flowrun.controllers import IDMController, ContinuousRouter,
RLController``, and Flow's module paths (``flowrun.controllers.car_following_models``,
``.velocity_controllers``, ``.routing_controllers``, ``.lane_change_controllers``,
``.base_controller``, ``.rlcontroller``). :class:`VehicleControllerView` is one vehicle's
controller with Flow's ``get_action(env)``. Controllers written Flow's way, per vehicle
(``BaseController.get_accel(env)``, ``BaseRouter.choose_route(env)``,
``BaseLaneChangeController.get_lane_change_action(env)``), are driven per vehicle as in Flow
(:mod:`flowrun.controllers.per_vehicle`).
"""

from flowrun.controllers.base import (
    AccelerationController,
    CarFollowingInputs,
    make_inputs,
    vehicle_limits,
)
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
from flowrun.controllers.car_following_formulas import (
    bando_ftl_accel,
    bcm_accel,
    cfm_accel,
    gipps_accel,
    idm_accel,
    linear_ovm_accel,
    ovm_accel,
)
from flowrun.controllers.i210_router import I210Router
from flowrun.controllers.lane_change import (
    LaneChangeController,
    SimLaneChangeController,
    StaticLaneChanger,
)
from flowrun.controllers.minicity_router import MinicityRouter
from flowrun.controllers.nonlocal_follower_stopper import NonLocalFollowerStopper
from flowrun.controllers.registry import (
    build_controller,
    controller_kind,
    controller_names,
    resolve_controller,
)
from flowrun.controllers.rl import RLController, SimCarFollowingController
from flowrun.controllers.routing import ContinuousRouter, GridRouter, Router, needs_new_route
from flowrun.controllers.velocity import (
    FollowerStopper,
    PISaturation,
    follower_stopper_speed,
    pi_saturation_speed,
)
from flowrun.controllers.view import VehicleControllerView

#: Flow's base-class names.
BaseController = AccelerationController
BaseRouter = Router
BaseLaneChangeController = LaneChangeController

__all__ = [
    "AccelerationController",
    "BCMController",
    "BandoFTLController",
    "BaseController",
    "BaseLaneChangeController",
    "BaseRouter",
    "CFMController",
    "CarFollowingInputs",
    "ContinuousRouter",
    "FollowerStopper",
    "GippsController",
    "GridRouter",
    "I210Router",
    "IDMController",
    "LACController",
    "LaneChangeController",
    "LinearOVM",
    "MinicityRouter",
    "NonLocalFollowerStopper",
    "OVMController",
    "PISaturation",
    "RLController",
    "Router",
    "SimCarFollowingController",
    "SimLaneChangeController",
    "StaticLaneChanger",
    "VehicleControllerView",
    "bando_ftl_accel",
    "bcm_accel",
    "build_controller",
    "cfm_accel",
    "controller_kind",
    "controller_names",
    "follower_stopper_speed",
    "gipps_accel",
    "idm_accel",
    "linear_ovm_accel",
    "make_inputs",
    "needs_new_route",
    "ovm_accel",
    "pi_saturation_speed",
    "resolve_controller",
    "vehicle_limits",
]
