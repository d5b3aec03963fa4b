"""Default experiments of the traffic-light grid envs: Flow's grid0 (3x3) and grid1 (5x5).

``gymnasium.make("flowrun/TrafficLightGridPOEnv-v0")`` without a config runs grid0, the same
experiment as ``configs/grid0.yaml`` (``flow/benchmarks/grid0.py``).
"""

from __future__ import annotations

from collections.abc import Callable

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

#: Flow's grid benchmarks: inflow per entry edge (veh/h), entry speed (m/s), horizon (steps).
EDGE_INFLOW, V_ENTER, HORIZON = 300, 30, 400


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
        env=EnvParams(additional_params=additional, horizon=HORIZON, env_class=env_class),
        network=NetworkConfig("traffic_light_grid", NetParams(net, inflows=inflows)),
        vehicles=vehicles,
        initial=InitialConfig(spacing="custom", shuffle=True),
    )


def _grid0(env_class: str) -> Callable[[], ExperimentConfig]:
    return lambda: grid_config(3, 3, env_class)


#: Default experiment of each grid env.
GRID_CONFIGS: dict[str, Callable[[], ExperimentConfig]] = {
    name: _grid0(name)
    for name in ("TrafficLightGridEnv", "TrafficLightGridPOEnv", "TrafficLightGridBenchmarkEnv")
}
