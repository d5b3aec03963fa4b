"""Default experiment of the bottleneck envs: Flow's bottleneck0.

``gymnasium.make("flowrun/BottleneckDesiredVelocityEnv-v0")`` (or ``BottleneckEnv``,
``BottleneckAccelEnv``, ``DesiredVelocityEnv``) without a config runs
:func:`bottleneck0_config`, the experiment of ``configs/bottleneck_desired_velocity.yaml``.
"""

from __future__ import annotations

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
    SumoLaneChangeParams,
    SumoParams,
    VehicleParams,
)
from flowrun.envs.bottleneck_accel import ADDITIONAL_RL_ENV_PARAMS
from flowrun.envs.bottleneck_velocity import ADDITIONAL_ENV_PARAMS

#: Flow's bottleneck0: total inflow (veh/h, times the scaling) and the share of AVs in it
FLOW_RATE, AV_FRAC = 2000, 0.1
#: Flow's cells: (edge, segments, controlled) and (edge, segments) observed
CONTROLLED = [("1", 1, False), ("2", 2, True), ("3", 2, True), ("4", 2, True), ("5", 1, False)]
OBSERVED = [("1", 1), ("2", 3), ("3", 3), ("4", 3), ("5", 1)]


def bottleneck0_config(env_name: str = "BottleneckDesiredVelocityEnv") -> ExperimentConfig:
    """Flow's ``flow/benchmarks/bottleneck0.py``: scaling 1, 2,000 veh/h of which 10 % AVs
    entering edge ``1`` in random lanes at 10 m/s, SUMO driving every car (speed mode 9, no
    lane changes), 0.5 s steps, 40 warm-up steps, horizon 1500; one car of each kind placed
    on edges ``2``-``5``."""
    vehicles = VehicleParams()
    for veh_id, controller in (("human", "SimCarFollowingController"), ("rl", "RLController")):
        vehicles.add(
            veh_id=veh_id,
            acceleration_controller=ControllerSpec(controller),
            routing_controller=ControllerSpec("ContinuousRouter"),
            car_following_params=SumoCarFollowingParams(speed_mode=9),
            lane_change_params=SumoLaneChangeParams(lane_change_mode=0),
            num_vehicles=1,
        )
    inflows = InFlows()
    for veh_type, share in (("human", 1 - AV_FRAC), ("rl", AV_FRAC)):
        inflows.add(edge="1", veh_type=veh_type, vehs_per_hour=share * FLOW_RATE,
                    depart_lane="random", depart_speed=10)  # fmt: skip
    params: dict[str, Any] = {
        **ADDITIONAL_ENV_PARAMS,
        **ADDITIONAL_RL_ENV_PARAMS,  # BottleneckAccelEnv's keys (the others ignore them)
        "target_velocity": 40,
        "controlled_segments": CONTROLLED,
        "observed_segments": OBSERVED,
        "inflow_range": [1200, 2500],
    }
    return ExperimentConfig(
        name="bottleneck0",
        sim=SumoParams(sim_step=0.5, seed=0),
        env=EnvParams(
            additional_params=params,
            horizon=1500,
            warmup_steps=40,
            sims_per_step=1,
            env_class=env_name,
        ),
        network=NetworkConfig(
            "bottleneck", NetParams({"scaling": 1, "speed_limit": 23}, inflows=inflows)
        ),
        vehicles=vehicles,
        initial=InitialConfig(spacing="uniform", min_gap=5, edges_distribution=list("2345")),
    )


def make_bottleneck(
    env_name: str, config: str | Path | ExperimentConfig | None = None, **kwargs: Any
) -> Any:
    """Gymnasium entry point of the bottleneck envs: :func:`bottleneck0_config` when no
    ``config`` is given, else as ``flowrun.envs.factory.make_registered``."""
    from flowrun.envs.factory import make_registered

    if config is None:
        config = bottleneck0_config(env_name)
    return make_registered(env_name, config=config, **kwargs)
