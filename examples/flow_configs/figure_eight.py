"""Example of a figure 8 network with human-driven vehicles.

Right-of-way dynamics near the intersection causes vehicles to queue up on
either side of the intersection, leading to a significant reduction in the
average speed of vehicles in the network.

Flow's ``examples/exp_configs/non_rl/figure_eight.py`` with its imports changed from ``flow``
to ``flowrun``.
"""
from flowrun.controllers import ContinuousRouter, IDMController, StaticLaneChanger
from flowrun.core.params import (
    EnvParams,
    NetParams,
    SumoCarFollowingParams,
    SumoParams,
    VehicleParams,
)
from flowrun.envs import AccelEnv
from flowrun.envs.ring.accel import ADDITIONAL_ENV_PARAMS
from flowrun.networks import FigureEightNetwork
from flowrun.networks.figure_eight import ADDITIONAL_NET_PARAMS

vehicles = VehicleParams()
vehicles.add(
    veh_id="idm",
    acceleration_controller=(IDMController, {
        "noise": 0.1,
    }),
    lane_change_controller=(StaticLaneChanger, {}),
    routing_controller=(ContinuousRouter, {}),
    car_following_params=SumoCarFollowingParams(
        speed_mode="obey_safe_speed",
        decel=1.5,
    ),
    initial_speed=0,
    num_vehicles=14)


flow_params = dict(
    # name of the experiment
    exp_tag='figure8',

    # name of the flow environment the experiment is running on
    env_name=AccelEnv,

    # name of the network class the experiment is running on
    network=FigureEightNetwork,

    # simulator that is used by the experiment
    simulator='traci',

    # sumo-related parameters (see flowrun.core.params.SumoParams)
    sim=SumoParams(
        render=True,
    ),

    # environment related parameters (see flowrun.core.params.EnvParams)
    env=EnvParams(
        horizon=1500,
        additional_params=ADDITIONAL_ENV_PARAMS.copy(),
    ),

    # network-related parameters (see flowrun.core.params.NetParams and the
    # network's documentation or ADDITIONAL_NET_PARAMS component)
    net=NetParams(
        additional_params=ADDITIONAL_NET_PARAMS.copy(),
    ),

    # vehicles to be placed in the network at the start of a rollout (see
    # flowrun.core.params.VehicleParams)
    veh=vehicles,
)
