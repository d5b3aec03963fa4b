"""Controllers through Flow's API: vehicle limits, Flow-style constructors, per-vehicle views.

No SUMO: the env is a small fake holding numbers; every expected value is worked out by hand
from Flow's formulas in the comments.
"""

from __future__ import annotations

import importlib
import math
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from flowrun.config.params import SumoCarFollowingParams
from flowrun.controllers import (
    BCMController,
    CFMController,
    ContinuousRouter,
    FollowerStopper,
    IDMController,
    OVMController,
    PISaturation,
    RLController,
    StaticLaneChanger,
    VehicleControllerView,
    build_controller,
    make_inputs,
)
from flowrun.controllers.fail_safe import obey_speed_limit
from flowrun.errors import ConfigError

INF = math.inf
RNG = np.random.default_rng(0)


def accel(ctrl: Any, inputs: Any) -> np.ndarray:
    return np.asarray(ctrl.get_accel(inputs, RNG))


@dataclass
class FakeVehicles:
    """``env.k.vehicle`` getters over plain dicts (a ring: car i follows car i+1)."""

    speed: dict[str, float]
    headway: dict[str, float]
    leader: dict[str, str | None]
    edge: dict[str, str] = field(default_factory=dict)
    position: dict[str, float] = field(default_factory=dict)

    def get_ids(self) -> list[str]:
        return list(self.speed)

    def get_speed(self, veh_id: str) -> float:
        return self.speed[veh_id]

    def get_headway(self, veh_id: str) -> float:
        return self.headway[veh_id]

    def get_leader(self, veh_id: str) -> str | None:
        return self.leader[veh_id]

    def get_follower(self, veh_id: str) -> str | None:
        return next((f for f, lead in self.leader.items() if lead == veh_id), None)

    def get_edge(self, veh_id: str) -> str:
        return self.edge.get(veh_id, "bottom")

    def get_position(self, veh_id: str) -> float:
        return self.position.get(veh_id, 0.0)

    def get_x_by_id(self, veh_id: str) -> float:
        return self.position.get(veh_id, 0.0)


def ring_env(speeds: list[float], headways: list[float], dt: float = 0.1) -> Any:
    ids = [f"car_{i}" for i in range(len(speeds))]
    vehicles = FakeVehicles(
        speed=dict(zip(ids, speeds, strict=True)),
        headway=dict(zip(ids, headways, strict=True)),
        leader={v: ids[(i + 1) % len(ids)] for i, v in enumerate(ids)},
    )
    network = SimpleNamespace(speed_limit=lambda edge: 30.0, edge_length=lambda edge: 57.5)
    return SimpleNamespace(k=SimpleNamespace(vehicle=vehicles, network=network), sim_step=dt)


# --- vehicle limits ------------------------------------------------------------------------


def test_pi_saturation_is_capped_at_the_vehicles_accel() -> None:
    # v=2, h=4, v_lead=6: dx_s = max(2*4, 4) = 8 -> alpha = 0, beta = 1 -> v_cmd = v_lead = 6
    # a = (6 - 2)/0.1 = 40; Flow returns min(40, accel) = 3 for accel = 3
    inp = make_inputs([2.0], [4.0], [6.0], dt=0.1)
    assert accel(PISaturation(), inp) == pytest.approx([40.0])  # limits unknown: uncapped
    assert accel(PISaturation(), make_inputs([2.0], [4.0], [6.0], max_accel=3.0)) == [3.0]
    cfp = SumoCarFollowingParams(accel=3.0, decel=5.0)
    assert accel(PISaturation(car_following_params=cfp), inp) == pytest.approx([3.0])


def test_pi_saturation_does_not_cap_braking() -> None:
    # v=4, h=6, v_lead=6.5: dx_s = 5, alpha = 0.5, beta = 0.75, U = 4, v_target = 4
    # v_cmd = 0.75*(0.5*4 + 0.5*6.5) = 3.9375 -> a = -0.625 (decel 0.1 does not clip it)
    inp = make_inputs([4.0], [6.0], [6.5], max_accel=3.0, max_decel=0.1)
    assert accel(PISaturation(), inp) == pytest.approx([-0.625])


def test_pi_saturation_history_holds_int_38_over_dt_minus_one_speeds() -> None:
    ctrl = PISaturation()
    ctrl.reset(1)
    for _ in range(3):
        accel(ctrl, make_inputs([1.0], [INF], dt=0.1))
    assert ctrl._history.shape == (379, 1)  # Flow drops the oldest when the list reaches 380


def test_follower_stopper_clips_to_vehicle_limits_and_runs_safe_velocity() -> None:
    # no leader: v_cmd = v_des = 15, v = 10 -> 50, clipped to accel 1.5
    # h = 3 <= dx_1 = 4.5: v_cmd = 0 -> -100, clipped to -decel = -4.5; safe velocity
    # 2*3/0.1 + 0 = 60 > 10 - 0.45, so the fail-safe keeps -4.5
    cfp = SumoCarFollowingParams(accel=1.5, decel=4.5)
    ctrl = FollowerStopper(car_following_params=cfp)
    assert ctrl.fail_safe == ("safe_velocity",)
    inp = make_inputs([10.0, 10.0], [INF, 3.0], [10.0, 10.0])
    assert accel(ctrl, inp) == pytest.approx([1.5, -4.5])


def test_feasible_accel_fail_safe_uses_the_vehicle_type_limits() -> None:
    # IDM from rest on a free road wants a = 1 -> accel 0.5; h = 1 at 10 m/s wants far
    # below -2 -> decel 2
    cfp = SumoCarFollowingParams(accel=0.5, decel=2.0)
    ctrl = IDMController(fail_safe="feasible_accel", car_following_params=cfp)
    inp = make_inputs([0.0, 10.0], [INF, 1.0], [0.0, 10.0])
    assert accel(ctrl, inp) == pytest.approx([0.5, -2.0])
    # the kernel's limits win over the constructor's
    inp = make_inputs([0.0], [INF], max_accel=0.25, max_decel=2.0)
    assert accel(ctrl, inp) == pytest.approx([0.25])


@pytest.mark.parametrize("cls", [CFMController, BCMController, OVMController])
def test_no_leader_commands_the_vehicles_accel(cls: Any) -> None:
    inp = make_inputs([5.0], [INF])
    assert accel(cls(), inp) == pytest.approx([2.6])  # unknown: SUMO's default
    assert accel(cls(), make_inputs([5.0], [INF], max_accel=1.7)) == pytest.approx([1.7])
    cfp = SumoCarFollowingParams(accel=0.9)
    assert accel(cls(car_following_params=cfp), inp) == pytest.approx([0.9])


def test_obey_speed_limit_stops_on_a_non_positive_limit() -> None:
    out = obey_speed_limit(np.array([1.0, 1.0]), np.array([5.0, 5.0]), np.array([0.0, 6.0]), 0.1)
    assert out == pytest.approx([-50.0, 1.0])  # -v/dt; (6 - 5)/0.1 = 10 > 1 keeps 1


# --- Flow-style constructors -----------------------------------------------------------------


def test_controllers_take_flows_leading_veh_id() -> None:
    cfp = SumoCarFollowingParams(accel=1.2, decel=3.0)
    idm = IDMController("human_0", car_following_params=cfp)
    assert (idm.veh_id, idm.max_accel, idm.max_deaccel) == ("human_0", 1.2, 3.0)
    cfm = CFMController("human_1", cfp, k_d=2)
    assert (cfm.veh_id, cfm.k_d, cfm.car_following_params) == ("human_1", 2.0, cfp)
    assert PISaturation("av_0", cfp).veh_id == "av_0"
    assert FollowerStopper("av_0", cfp, v_des=7.5).v_des == 7.5
    assert RLController("rl_0", cfp).veh_id == "rl_0"
    assert ContinuousRouter("human_0", None).veh_id == "human_0"
    assert StaticLaneChanger("human_0").veh_id == "human_0"
    # Flow's controller_params dict is read too; decel is taken positive
    flow_like = SimpleNamespace(controller_params={"accel": 2.0, "decel": -4.0})
    assert IDMController("x", car_following_params=flow_like).max_deaccel == 4.0
    assert IDMController().max_accel == 2.6  # Flow's SumoCarFollowingParams default


def test_config_path_refuses_flow_only_arguments() -> None:
    assert build_controller("IDM", {"v0": 20}).v0 == 20
    with pytest.raises(ConfigError, match="unknown parameter 'veh_id'"):
        build_controller("IDM", {"veh_id": "x"})
    cfp = SumoCarFollowingParams(accel=1.1)
    built = build_controller("CFM", {}, veh_id="g_0", car_following_params=cfp)
    assert (built.veh_id, built.max_accel) == ("g_0", 1.1)


def test_flow_module_paths_export_flowruns_classes() -> None:
    expected = {
        "car_following_models": ["IDMController", "OVMController", "BCMController", "LinearOVM",
                                 "CFMController", "GippsController", "BandoFTLController",
                                 "SimCarFollowingController"],
        "velocity_controllers": ["FollowerStopper", "PISaturation"],
        "routing_controllers": ["ContinuousRouter"],
        "lane_change_controllers": ["StaticLaneChanger", "SimLaneChangeController"],
        "base_controller": ["BaseController"],
        "rlcontroller": ["RLController"],
        "base_routing_controller": ["BaseRouter"],
        "base_lane_changing_controller": ["BaseLaneChangeController"],
    }  # fmt: skip
    package = importlib.import_module("flowrun.controllers")
    for module_name, names in expected.items():
        module = importlib.import_module(f"flowrun.controllers.{module_name}")
        for name in names:
            assert getattr(module, name) is getattr(package, name)


# --- the per-vehicle view --------------------------------------------------------------------


def test_view_get_action_matches_idm_by_hand() -> None:
    # car_0: v=5, h=20, v_lead=5: s* = 2 + 5*1 = 7; a = 1 - (5/30)^4 - (7/20)^2 = 0.8767284
    # car_1: v=5, h=10, v_lead=10: s* = 2 + max(0, 5 + 5*(-5)/(2*sqrt(1.5))) = 2
    #        a = 1 - (1/6)^4 - (2/10)^2 = 0.9592284
    env = ring_env([5.0, 5.0, 10.0], [20.0, 10.0, 40.0])
    ctrl = IDMController()
    actions = [VehicleControllerView(ctrl, v).get_action(env) for v in ("car_0", "car_1")]
    assert actions == pytest.approx([1 - (1 / 6) ** 4 - 0.35**2, 1 - (1 / 6) ** 4 - 0.04])


def test_view_uses_the_vehicle_limits_for_pi_saturation() -> None:
    # car_0: v=2, h=4, leader car_1 at 6 m/s -> 40 uncapped, Flow's min(40, accel=3) = 3
    env = ring_env([2.0, 6.0], [4.0, 50.0])
    cfp = SumoCarFollowingParams(accel=3.0, decel=5.0)
    view = VehicleControllerView(PISaturation(), "car_0", cfp)
    assert view.get_action(env) == pytest.approx(3.0)
    assert (view.max_accel, view.max_deaccel) == (3.0, 5.0)


def test_view_bcm_reads_the_followers_gap() -> None:
    # car_1: h = 10, follower car_0 has h = 4; all at 0 m/s; v_des = 8:
    # a = 1*(10 - 4) + 1*((0 - 0) - (0 - 0)) + 1*(8 - 0) = 14
    env = ring_env([0.0, 0.0, 0.0], [4.0, 10.0, 30.0])
    assert VehicleControllerView(BCMController(), "car_1").get_action(env) == pytest.approx(14.0)


def test_view_without_leader_gives_max_accel_and_no_command_off_the_road() -> None:
    env = ring_env([5.0, 5.0], [INF, INF])
    env.k.vehicle.leader = {"car_0": None, "car_1": None}
    view = VehicleControllerView(OVMController(), "car_0", SumoCarFollowingParams(accel=1.3))
    assert view.get_action(env) == pytest.approx(1.3)
    env.k.vehicle.edge["car_0"] = ":center_0"
    assert view.get_action(env) is None  # junction-internal edge: SUMO drives
    env.k.vehicle.edge["car_0"] = ""
    assert view.get_action(env) is None
    assert VehicleControllerView(RLController(), "car_1").get_action(env) is None


def test_view_find_intersection_dist_and_danger_edges() -> None:
    env = ring_env([5.0, 5.0], [20.0, 20.0])
    env.k.vehicle.position["car_0"] = 50.0
    view = VehicleControllerView(FollowerStopper(danger_edges=["bottom"]), "car_0")
    assert view.find_intersection_dist(env) == pytest.approx(7.5)  # 57.5 - 50
    assert view.get_action(env) is None  # within 10 m of the end of a danger edge
    env.k.vehicle.edge["car_0"] = "center_in"
    assert view.find_intersection_dist(env) == 0.0
    env.k.vehicle.edge["car_0"] = ""
    assert view.find_intersection_dist(env) == -10.0


def test_view_keeps_its_own_memory_for_stateful_controllers() -> None:
    group = PISaturation()
    group.reset(4)
    env = ring_env([2.0, 6.0], [4.0, 50.0])
    view = VehicleControllerView(group, "car_0")
    view.get_action(env)
    assert group.v_cmd.shape == (4,) and not group.v_cmd.any()  # the group is untouched
    assert view.controller is not group and view.v_cmd == pytest.approx([6.0])
    assert view.veh_id == "car_0" and view.v_catch == 1.0  # parameters read through
