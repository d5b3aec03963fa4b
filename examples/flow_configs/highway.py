"""Example of an open multi-lane network with human-driven vehicles.

Flow's ``examples/exp_configs/non_rl/highway.py`` with its imports changed from ``flow`` to
``flowrun``; the environment and network are named by string, as there.
"""

from flowrun.controllers import IDMController
from flowrun.core.params import (
    EnvParams,
    InFlows,
    InitialConfig,
    NetParams,
    SumoParams,
    VehicleParams,
)
from flowrun.envs.ring.lane_change_accel import ADDITIONAL_ENV_PARAMS
from flowrun.networks.highway import ADDITIONAL_NET_PARAMS

vehicles = VehicleParams()
vehicles.add(
    veh_id="human",
    acceleration_controller=(IDMController, {}),
    num_vehicles=20)
vehicles.add(
    veh_id="human2",
    acceleration_controller=(IDMController, {}),
    num_vehicles=20)

env_params = EnvParams(additional_params=ADDITIONAL_ENV_PARAMS)

inflow = InFlows()
inflow.add(
    veh_type="human",
    edge="highway_0",
    probability=0.25,
    departLane="free",
    departSpeed=20)
inflow.add(
    veh_type="human2",
    edge="highway_0",
    probability=0.25,
    departLane="free",
    departSpeed=20)


flow_params = dict(
    # name of the experiment
    exp_tag='highway',

    # name of the flow environment the experiment is running on
    env_name='LaneChangeAccelEnv',

    # name of the network class the experiment is running on
    network='HighwayNetwork',

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
        inflows=inflow,
        additional_params=ADDITIONAL_NET_PARAMS.copy(),
    ),

    # vehicles to be placed in the network at the start of a rollout (see
    # flowrun.core.params.VehicleParams)
    veh=vehicles,

    # parameters specifying the positioning of vehicles upon initialization/
    # reset (see flowrun.core.params.InitialConfig)
    initial=InitialConfig(
        spacing="uniform",
        shuffle=True,
    ),
)
