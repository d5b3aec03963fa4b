"""Flow's ``flow.utils.rllib``: ``flow_params`` through JSON (``FlowParamsEncoder``) and back
(``get_flow_params``), for flowrun's own dicts and for a JSON file in Flow's layout."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path
from typing import Any

import pytest

from flowrun.controllers import ContinuousRouter, IDMController, RLController
from flowrun.core.params import (
    EnvParams,
    InFlows,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    TrafficLightParams,
    VehicleParams,
)
from flowrun.envs import AccelEnv, WaveAttenuationPOEnv
from flowrun.networks import MergeNetwork, RingNetwork
from flowrun.utils.rllib import FlowParamsEncoder, get_flow_params


def flow_params() -> dict[str, Any]:
    veh = VehicleParams()
    veh.add(
        "idm", acceleration_controller=(IDMController, {"v0": 20, "noise": 0.2}),
        routing_controller=(ContinuousRouter, {}),
        car_following_params=SumoCarFollowingParams(accel=1.5, min_gap=0, speed_mode="aggressive"),
        lane_change_params=SumoLaneChangeParams(model="SL2015", lc_pushy=0.3,
                                                lane_change_mode="sumo_default"),
        num_vehicles=21,
    )  # fmt: skip
    veh.add("rl", acceleration_controller=(RLController, {}), num_vehicles=1)
    inflows = InFlows()
    inflows.add("bottom", "idm", vehs_per_hour=300, depart_speed=5)
    tls = TrafficLightParams()
    tls.add("right", phases=[{"duration": "31", "state": "G"}])
    return dict(
        exp_tag="ring", env_name=AccelEnv, network=RingNetwork, simulator="traci",
        sim=SumoParams(sim_step=0.2, seed=3),
        env=EnvParams(horizon=100, additional_params={"max_accel": 1, "max_decel": 1,
                                                      "target_velocity": 10,
                                                      "sort_vehicles": False}),
        net=NetParams(additional_params={"length": 230}, inflows=inflows),
        veh=veh, initial=InitialConfig(bunching=20), tls=tls,
    )  # fmt: skip


def test_round_trip_through_rllibs_env_config_and_a_file(tmp_path: Path) -> None:
    fp = flow_params()
    text = json.dumps(fp, cls=FlowParamsEncoder)
    (tmp_path / "params.json").write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # flowrun's own JSON uses no deprecated spelling
        for back in (get_flow_params({"env_config": {"flow_params": text}}),
                     get_flow_params(tmp_path / "params.json")):  # fmt: skip
            for key in ("sim", "env", "initial"):
                assert back[key] == fp[key]
            assert back["net"].additional_params == {"length": 230}
            assert back["net"].inflows.get() == fp["net"].inflows.get()
            assert back["veh"].groups == fp["veh"].groups
            assert back["veh"].groups[0].acceleration_controller.cls is IDMController
            assert back["tls"].get_properties() == fp["tls"].get_properties()
            assert back["env_name"] is AccelEnv and back["network"] is RingNetwork
            assert back["exp_tag"] == "ring"


def test_json_uses_flows_layout() -> None:
    data = json.loads(json.dumps(flow_params(), cls=FlowParamsEncoder))
    assert data["env_name"] == "AccelEnv" and data["network"] == "RingNetwork"
    group = data["veh"][0]
    assert group["acceleration_controller"] == ["IDMController", {"v0": 20, "noise": 0.2}]
    assert group["routing_controller"] == ["ContinuousRouter", {}]
    assert group["car_following_params"]["controller_params"]["minGap"] == 0
    assert group["car_following_params"]["speed_mode"] == 0  # Flow's "aggressive"
    assert group["lane_change_params"]["lane_change_mode"] == 1621  # Flow's "sumo_default"
    assert "_InFlows__flows" in data["net"]["inflows"]


FLOW_WRITTEN = {
    "exp_tag": "stabilizing_the_ring", "env_name": "WaveAttenuationPOEnv",
    "network": "RingNetwork", "simulator": "traci",
    "sim": {"port": None, "sim_step": 0.1, "render": False, "restart_instance": False,
            "emission_path": None, "seed": None, "print_warnings": True, "teleport_time": -1,
            "num_clients": 1, "force_color_update": False},
    "env": {"horizon": 3000, "warmup_steps": 750, "sims_per_step": 1, "evaluate": False,
            "clip_actions": False,
            "additional_params": {"max_accel": 1, "max_decel": 1, "ring_length": [220, 270]}},
    "net": {"inflows": {"_InFlows__flows": [
                {"name": "flow_0", "vtype": "human", "edge": "inflow_highway",
                 "departLane": "free", "departSpeed": 10, "begin": 1, "end": 86400,
                 "vehsPerHour": 2000}]},
            "osm_path": None, "template": None,
            "additional_params": {"length": 260, "lanes": 1, "speed_limit": 30,
                                  "resolution": 40}},
    "veh": [{"veh_id": "human",
             "acceleration_controller": ["IDMController", {"noise": 0.2}],
             "lane_change_controller": ["SimLaneChangeController", {}],
             "routing_controller": ["ContinuousRouter", {}],
             "initial_speed": 0, "num_vehicles": 21,
             "car_following_params": {"controller_params": {
                 "accel": 1.0, "decel": 1.5, "sigma": 0.5, "tau": 1.0, "minGap": 0,
                 "maxSpeed": 30, "speedFactor": 1.0, "speedDev": 0.1, "impatience": 0.5,
                 "carFollowModel": "IDM"}, "speed_mode": 1},
             "lane_change_params": {"controller_params": {
                 "laneChangeModel": "LC2013", "lcStrategic": "1.0", "lcCooperative": "1.0",
                 "lcSpeedGain": "1.0", "lcKeepRight": "1.0"}, "lane_change_mode": 512}}],
    "initial": {"shuffle": False, "spacing": "uniform", "min_gap": 0, "perturbation": 0.0,
                "x0": 0, "bunching": 0, "lanes_distribution": math.inf,
                "edges_distribution": "all", "additional_params": {}},
    "tls": {"_TrafficLightParams__tls_properties": {}, "baseline": False},
}  # fmt: skip


def test_a_json_file_written_by_flow_loads(tmp_path: Path) -> None:
    path = tmp_path / "flow_params.json"
    path.write_text(json.dumps(FLOW_WRITTEN))
    with pytest.warns(DeprecationWarning):  # Flow's camelCase inflow keys, as Flow warns
        fp = get_flow_params(str(path))
    assert fp["env_name"] is WaveAttenuationPOEnv and fp["network"] is RingNetwork
    assert fp["env"].warmup_steps == 750 and fp["env"].clip_actions is False
    assert fp["env"].additional_params["ring_length"] == [220, 270]
    cf = fp["veh"].groups[0].car_following_params
    assert (cf.accel, cf.decel, cf.min_gap, cf.speed_dev, int(cf.speed_mode)) == (
        1.0, 1.5, 0, 0.1, 1)  # fmt: skip
    lc = fp["veh"].groups[0].lane_change_params
    assert (lc.model, lc.lc_strategic, int(lc.lane_change_mode)) == ("LC2013", 1.0, 512)
    assert fp["veh"].groups[0].acceleration_controller.cls is IDMController
    assert fp["veh"].groups[0].acceleration_controller.params == {"noise": 0.2}
    (flow,) = fp["net"].inflows.get()
    assert (flow.edge, flow.veh_type, flow.vehs_per_hour, flow.depart_lane) == (
        "inflow_highway", "human", 2000, "free")  # fmt: skip
    assert fp["initial"].lanes_distribution == math.inf
    assert fp["net"].additional_params["length"] == 260
    assert MergeNetwork is not fp["network"]
