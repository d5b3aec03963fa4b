"""Default experiments of the built-in envs that do not run on the ring.

``gymnasium.make("flowrun/<Env>-v0")`` without a config runs: for ``MergePOEnv`` Flow's
merge0 benchmark (:func:`merge0_config`, the same experiment as ``configs/merge.yaml``); for
the bottleneck envs Flow's bottleneck0 (:func:`bottleneck0_config`, the experiment of
``configs/bottleneck_desired_velocity.yaml``); for the grid envs Flow's grid0
(:func:`grid_config`, as ``configs/grid0.yaml``). The ring envs keep
:func:`flowrun.envs.factory.default_config`.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
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
from flowrun.envs.bottleneck import ADDITIONAL_RL_ENV_PARAMS, BottleneckDesiredVelocityEnv
from flowrun.envs.factory import make_registered

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


#: Flow's bottleneck0: total inflow (veh/h, times the scaling) and the share of AVs in it
BOTTLENECK_FLOW_RATE, BOTTLENECK_AV_FRAC = 2000, 0.1
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
    for veh_type, share in (("human", 1 - BOTTLENECK_AV_FRAC), ("rl", BOTTLENECK_AV_FRAC)):
        inflows.add(edge="1", veh_type=veh_type, vehs_per_hour=share * BOTTLENECK_FLOW_RATE,
                    depart_lane="random", depart_speed=10)  # fmt: skip
    params: dict[str, Any] = {
        **BottleneckDesiredVelocityEnv.ADDITIONAL_ENV_PARAMS,
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


#: Flow's grid benchmarks: inflow per entry edge (veh/h), entry speed (m/s), horizon (steps).
EDGE_INFLOW, V_ENTER, GRID_HORIZON = 300, 30, 400


def entry_edges(rows: int, cols: int) -> list[str]:
    """The grid's entry edges in Flow's order (from the top, bottom, left, right)."""
    return (
        [f"left{rows}_{j}" for j in range(cols)]
        + [f"right0_{j}" for j in range(cols)]
        + [f"bot{i}_0" for i in range(rows)]
        + [f"top{i}_{cols}" for i in range(rows)]
    )


def grid_config(
    rows: int = 3, cols: int = 3, env_class: str = "TrafficLightGridBenchmarkEnv"
) -> ExperimentConfig:
    """Flow's grid0 (3x3) / grid1 (5x5) benchmark as a config (see ``configs/grid0.yaml``)."""
    vehicles = VehicleParams()
    vehicles.add(
        veh_id="human",
        acceleration_controller=ControllerSpec("SimCarFollowingController"),
        routing_controller=ControllerSpec("GridRouter"),
        num_vehicles=2 * cols + 2 * rows,
        car_following_params=SumoCarFollowingParams(
            min_gap=2.5, max_speed=V_ENTER, decel=7.5, speed_mode="right_of_way", speed_dev=0.1
        ),
    )
    inflows = InFlows()
    for edge in entry_edges(rows, cols):
        inflows.add(
            edge, "human", vehs_per_hour=EDGE_INFLOW, depart_lane="free", depart_speed=V_ENTER
        )
    grid = {
        "short_length": 300,
        "inner_length": 300,
        "long_length": 100,
        "row_num": rows,
        "col_num": cols,
        "cars_left": 1,
        "cars_right": 1,
        "cars_top": 1,
        "cars_bot": 1,
    }
    net = {
        "speed_limit": V_ENTER + 5,
        "grid_array": grid,
        "horizontal_lanes": 1,
        "vertical_lanes": 1,
    }
    additional = {
        "target_velocity": 50,
        "switch_time": 3,
        "num_observed": 2,
        "discrete": False,
        "tl_type": "actuated",
    }
    return ExperimentConfig(
        name="grid0" if (rows, cols) == (3, 3) else f"grid_{rows}x{cols}",
        sim=SumoParams(sim_step=1.0, seed=0),
        env=EnvParams(additional_params=additional, horizon=GRID_HORIZON, env_class=env_class),
        network=NetworkConfig("traffic_light_grid", NetParams(net, inflows=inflows)),
        vehicles=vehicles,
        initial=InitialConfig(spacing="custom", shuffle=True),
    )


#: the envs that run Flow's bottleneck0 / grid0 by default
BOTTLENECK_ENVS = (
    "BottleneckEnv", "BottleneckAccelEnv", "BottleneckDesiredVelocityEnv", "DesiredVelocityEnv",
)  # fmt: skip
GRID_ENVS = ("TrafficLightGridEnv", "TrafficLightGridPOEnv", "TrafficLightGridBenchmarkEnv")

#: Default experiment of each built-in env that has its own (others: the ring).
DEFAULT_CONFIGS: dict[str, Callable[[], ExperimentConfig]] = {
    "MergePOEnv": merge0_config,
    **{name: partial(bottleneck0_config, name) for name in BOTTLENECK_ENVS},
    **{name: partial(grid_config, 3, 3, name) for name in GRID_ENVS},
}


def make_with_default(
    env_name: str, config: str | Path | ExperimentConfig | None = None, **kwargs: Any
) -> Any:
    """Gymnasium entry point of every built-in env: its own default experiment
    (:data:`DEFAULT_CONFIGS`; the ring for the others) when no ``config`` is given, else as
    :func:`flowrun.envs.factory.make_registered`."""
    if config is None and env_name in DEFAULT_CONFIGS:
        config = DEFAULT_CONFIGS[env_name]()
    return make_registered(env_name, config=config, **kwargs)
