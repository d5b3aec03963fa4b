"""The shipped configs that mirror a Flow example or benchmark build Flow's vehicle types.

flowrun's ``SumoCarFollowingParams`` defaults differ from Flow's on purpose (speed mode 0,
decel 7.5, speedDev 0; the ring configs rely on them), so a config that reproduces a Flow
set-up states every value Flow's file leaves at Flow's defaults. Each expectation below is
``SumoCarFollowingParams(...)`` as the Flow file named beside it calls it, on top of Flow's
defaults of its last version (flow/core/params.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from flowrun.config.vtype import vtype_attributes
from flowrun.envs.defaults import grid_config, merge0_config
from flowrun.loading.loader import load_config

CONFIGS = Path(__file__).resolve().parent.parent / "configs"

#: Flow's SumoCarFollowingParams() of its last version
FLOW_DEFAULT_VTYPE = {"accel": 2.6, "decel": 4.5, "sigma": 0.5, "tau": 1.0, "minGap": 2.5,
                      "maxSpeed": 30.0, "speedFactor": 1.0, "speedDev": 0.1,
                      "impatience": 0.5}  # fmt: skip


def flow_vtype(speed_mode: int, lc_mode: int = 512, **changes: float) -> dict[str, Any]:
    """Flow's vType for ``SumoCarFollowingParams(speed_mode=..., **changes)`` and
    ``SumoLaneChangeParams(lane_change_mode=lc_mode)`` (SUMO's names; Flow's default lane-change
    mode is no_lc_safe, 512)."""
    return {"speedMode": speed_mode, "laneChangeMode": lc_mode, **FLOW_DEFAULT_VTYPE, **changes}


# merge0/1/2.py: SumoCarFollowingParams(speed_mode=9) for humans and AVs
MERGE = {"human": flow_vtype(9), "rl": flow_vtype(9)}
# figureeight0/1/2.py of Flow's last version: humans (speed_mode="obey_safe_speed",
# decel=1.5), AVs (speed_mode="obey_safe_speed")
FIGURE_EIGHT = {"human": flow_vtype(1, decel=1.5), "rl": flow_vtype(1)}
#: Flow's SumoCarFollowingParams() at the paper's commit (bc44b21, 2018), which the figure-eight
#: benchmarks keep (speed mode 1, "no_collide" then); an IDM-driven car's minGap was 0
FLOW_2018 = {"accel": 1.0, "decel": 1.5}
PAPER_FIGURE_EIGHT = {"human": flow_vtype(1, **FLOW_2018, minGap=0.0),
                      "rl": flow_vtype(1, **FLOW_2018)}  # fmt: skip
# grid0/1.py, multiagent_traffic_light_grid.py: (min_gap=2.5, max_speed=30, decel=7.5,
# speed_mode="right_of_way")
GRID = {"human": flow_vtype(25, decel=7.5)}

EXPECTED: dict[str, dict[str, dict[str, Any]]] = {
    "merge": MERGE,
    "benchmarks/merge0": MERGE,
    "benchmarks/merge1": MERGE,
    "benchmarks/merge2": MERGE,
    "figure_eight_rl": FIGURE_EIGHT,
    "benchmarks/figureeight0": PAPER_FIGURE_EIGHT,
    "benchmarks/figureeight1": PAPER_FIGURE_EIGHT,
    "benchmarks/figureeight2": {"rl": PAPER_FIGURE_EIGHT["rl"]},
    # non_rl/figure_eight.py: (speed_mode="obey_safe_speed", decel=1.5)
    "figure_eight": {"idm": flow_vtype(1, decel=1.5)},
    "grid0": GRID,
    "grid1": GRID,
    "benchmarks/grid0": GRID,
    "benchmarks/grid1": GRID,
    "multiagent_grid": GRID,
    # multiagent_merge.py: (speed_mode="obey_safe_speed") for humans and AVs
    "multiagent_merge": {"human": flow_vtype(1), "rl": flow_vtype(1)},
    "rllib_multiagent_merge": {"human": flow_vtype(1), "rl": flow_vtype(1)},
    # non_rl/highway_ramps.py: (speed_mode="obey_safe_speed", tau=1.5), lane-change mode 1621;
    # flowrun's documented deviation: right of way (25) at the merge
    "highway_ramps": {"human": flow_vtype(25, 1621, tau=1.5)},
    # non_rl/minicity.py: speed mode 1 / obey_safe_speed; flowrun's documented deviations:
    # right of way (25) and impatience 0 at the junctions
    "minicity": {"idm": flow_vtype(25, impatience=0.0), "rl": flow_vtype(25, impatience=0.0)},
    # non_rl/highway.py's humans: SumoCarFollowingParams() (right_of_way); flowrun's variant
    # adds SUMO lane changes (sumo_default) and AVs (obey_safe_speed)
    "highway_lane_change": {"human": flow_vtype(25, 1621), "rl": flow_vtype(1)},
}


def group_kind(veh_id: str) -> str:
    """``human3`` -> ``human`` (figureeight1 alternates human0, rl0, human1, ...)."""
    return veh_id.rstrip("0123456789")


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_flow_mirroring_configs_build_flows_vehicle_types(name: str) -> None:
    groups = load_config(CONFIGS / f"{name}.yaml").vehicles.groups
    assert {group_kind(g.veh_id) for g in groups} == set(EXPECTED[name])
    for g in groups:
        attrs = vtype_attributes(g.car_following_params, g.lane_change_params)
        found = {"speedMode": g.car_following_params.speed_mode,
                 "laneChangeMode": g.lane_change_params.lane_change_mode}  # fmt: skip
        found.update({k: float(attrs[k]) for k in FLOW_DEFAULT_VTYPE})
        assert found == EXPECTED[name][group_kind(g.veh_id)], g.veh_id
        assert (attrs["carFollowModel"], attrs["laneChangeModel"]) == ("IDM", "LC2013")


def test_figureeight1_alternates_seven_humans_and_seven_avs() -> None:
    groups = load_config(CONFIGS / "benchmarks/figureeight1.yaml").vehicles.groups
    assert [g.veh_id for g in groups] == [f"{k}{i}" for i in range(7) for k in ("human", "rl")]
    assert all(g.num_vehicles == 1 for g in groups)


def test_python_defaults_of_merge_and_grid_envs_build_the_configs_vehicle_types() -> None:
    # gymnasium.make("flowrun/MergePOEnv-v0") / the grid envs without a config run these
    assert merge0_config().vehicles == load_config(CONFIGS / "merge.yaml").vehicles
    for rows, name in ((3, "grid0"), (5, "grid1")):
        assert grid_config(rows, rows).vehicles == load_config(CONFIGS / f"{name}.yaml").vehicles


@pytest.mark.parametrize("name", ["multiagent_merge", "rllib_multiagent_merge"])
def test_multiagent_merge_is_flows_multiagent_merge_example(name: str) -> None:
    # examples/exp_configs/rl/multiagent/multiagent_merge.py (EXP_NUM 0)
    cfg = load_config(CONFIGS / f"{name}.yaml")
    assert (cfg.sim.sim_step, cfg.env.sims_per_step, cfg.env.horizon) == (0.2, 5, 600)
    assert cfg.env.warmup_steps == 0
    human, rl = cfg.vehicles.groups
    assert (human.acceleration_controller.type, human.acceleration_controller.params) == (
        "IDM", {"noise": 0.2})  # fmt: skip
    assert (human.num_vehicles, rl.num_vehicles, rl.acceleration_controller.type) == (
        5, 0, "RLController")  # fmt: skip
    inflows = cfg.network.net_params.inflows
    assert inflows is not None
    rates = [(f.edge, f.veh_type, f.vehs_per_hour, f.depart_lane, f.depart_speed)
             for f in inflows.get()]  # fmt: skip
    assert rates == [("inflow_highway", "human", 1800, "free", 10),
                     ("inflow_highway", "rl", 200, "free", 10),
                     ("inflow_merge", "human", 100, "free", 7.5)]  # fmt: skip
