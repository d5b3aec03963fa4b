"""Default experiments of the built-in envs that do not run on the ring.

``gymnasium.make("flowrun/MergePOEnv-v0")`` without a config runs Flow's merge0 benchmark
(:func:`merge0_config`, the same experiment as ``configs/merge.yaml``); the ring envs keep
:func:`flowrun.envs.factory.default_config`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from flowrun.config.model import ExperimentConfig, NetworkConfig
from flowrun.config.params import (
    ControllerSpec,
    EnvParams,
    InFlows,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoParams,
    VehicleParams,
)
from flowrun.envs.grid_defaults import GRID_CONFIGS

#: Flow's merge0: inflow on the highway (veh/h), share of AVs in it, inflow on the ramp (veh/h)
MERGE_FLOW_RATE, MERGE_RL_PENETRATION, MERGE_RAMP_RATE = 2000, 0.1, 100
#: SUMO speed mode of every car in Flow's merge benchmarks: safe speed and right of way
MERGE_SPEED_MODE = 9


def merge0_config(
    num_rl: int = 5, rl_penetration: float = MERGE_RL_PENETRATION
) -> ExperimentConfig:
    """Flow's merge benchmark (``flow/benchmarks/merge0.py``; merge1/2: ``num_rl`` 13/17
    with ``rl_penetration`` 0.25/0.333).

    Single-lane highway (``pre_merge_length`` 500 m) and ramp; 2,000 veh/h on the highway of
    which ``rl_penetration`` AVs, 100 veh/h on the ramp, 5 humans placed at the start; humans
    driven by SUMO; 0.5 s steps, 2 per env step, 750 env steps.
    """
    vehicles = VehicleParams()
    # Flow's SumoCarFollowingParams(speed_mode=9): Flow's decel and speedDev, not flowrun's
    cf = SumoCarFollowingParams(speed_mode=MERGE_SPEED_MODE, decel=4.5, speed_dev=0.1)
    vehicles.add(
        veh_id="human",
        acceleration_controller=ControllerSpec("SimCarFollowingController"),
        car_following_params=cf,
        num_vehicles=5,
    )
    vehicles.add(
        veh_id="rl",
        acceleration_controller=ControllerSpec("RLController"),
        car_following_params=cf,
        num_vehicles=0,
    )
    inflows = InFlows()
    for veh_type, rate in (
        ("human", (1 - rl_penetration) * MERGE_FLOW_RATE),
        ("rl", rl_penetration * MERGE_FLOW_RATE),
    ):
        inflows.add(
            edge="inflow_highway", veh_type=veh_type, vehs_per_hour=rate, depart_lane="free",
            depart_speed=10,
        )  # fmt: skip
    inflows.add(
        edge="inflow_merge", veh_type="human", vehs_per_hour=MERGE_RAMP_RATE, depart_lane="free",
        depart_speed=7.5,
    )  # fmt: skip
    net = {
        "merge_length": 100, "pre_merge_length": 500, "post_merge_length": 100,
        "merge_lanes": 1, "highway_lanes": 1, "speed_limit": 30,
    }  # fmt: skip
    return ExperimentConfig(
        name="merge",
        sim=SumoParams(sim_step=0.5, seed=0),
        env=EnvParams(
            additional_params={
                "max_accel": 1.5,
                "max_decel": 1.5,
                "target_velocity": 20,
                "num_rl": num_rl,
            },
            horizon=750,
            sims_per_step=2,
            warmup_steps=0,
            env_class="MergePOEnv",
        ),
        network=NetworkConfig("merge", NetParams(net, inflows=inflows)),
        vehicles=vehicles,
        initial=InitialConfig(spacing="uniform"),
    )


#: Default experiment of each built-in env that has its own (others: the ring).
DEFAULT_CONFIGS: dict[str, Callable[[], ExperimentConfig]] = {
    "MergePOEnv": merge0_config,
    **GRID_CONFIGS,
}


def make_with_default(
    env_name: str, config: str | Path | ExperimentConfig | None = None, **kwargs: Any
) -> Any:
    """Gymnasium entry point of the envs in :data:`DEFAULT_CONFIGS`: their own default
    experiment when no ``config`` is given, else as ``flowrun.envs.factory.make_registered``."""
    from flowrun.envs.factory import make_registered

    if config is None:
        config = DEFAULT_CONFIGS[env_name]()
    return make_registered(env_name, config=config, **kwargs)
