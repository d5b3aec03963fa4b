"""Used as an example of ring experiment.

This example consists of 22 IDM cars on a ring creating shockwaves.

Flow's ``examples/exp_configs/non_rl/ring.py`` with its imports changed from ``flow`` to
``flowrun``: run it with ``flowrun baseline examples/flow_configs/ring.py`` or convert it with
``flowrun convert examples/flow_configs/ring.py``.
"""

from flowrun.controllers import ContinuousRouter, IDMController
from flowrun.core.params import EnvParams, InitialConfig, NetParams, SumoParams, VehicleParams
from flowrun.envs.ring.accel import ADDITIONAL_ENV_PARAMS, AccelEnv
from flowrun.networks.ring import ADDITIONAL_NET_PARAMS, RingNetwork

vehicles = VehicleParams()
vehicles.add(
    veh_id="idm",
    acceleration_controller=(IDMController, {}),
    routing_controller=(ContinuousRouter, {}),
    num_vehicles=22)


flow_params = dict(
    # name of the experiment
    exp_tag='ring',

    # name of the flow environment the experiment is running on
    env_name=AccelEnv,

    # name of the network class the experiment is running on
    network=RingNetwork,

    # simulator that is used by the experiment
    simulator='traci',

    # sumo-related parameters (see flowrun.core.params.SumoParams)
    sim=SumoParams(
        render=True,
        sim_step=0.1,
    ),

    # environment related parameters (see flowrun.core.params.EnvParams)
    env=EnvParams(
        horizon=1500,
        additional_params=ADDITIONAL_ENV_PARAMS,
    ),

    # network-related parameters (see flowrun.core.params.NetParams and the
    # network's documentation or ADDITIONAL_NET_PARAMS component)
    net=NetParams(
        additional_params=ADDITIONAL_NET_PARAMS.copy(),
    ),

    # vehicles to be placed in the network at the start of a rollout (see
    # flowrun.core.params.VehicleParams)
    veh=vehicles,

    # parameters specifying the positioning of vehicles upon initialization/
    # reset (see flowrun.core.params.InitialConfig)
    initial=InitialConfig(
        bunching=20,
    ),
)
