"""Controllers written Flow's way (one object per vehicle, ``get_accel(env)``,
``choose_route(env)``, ``get_lane_change_action(env)``) drive their cars in flowrun as in
Flow (real SUMO, short seeded runs)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from flowrun.controllers import (
    BaseController,
    BaseLaneChangeController,
    BaseRouter,
    ContinuousRouter,
    IDMController,
)
from flowrun.controllers.per_vehicle import PerVehicleGroup
from flowrun.core.params import (
    EnvParams,
    InitialConfig,
    NetParams,
    SumoCarFollowingParams,
    SumoLaneChangeParams,
    SumoParams,
    VehicleParams,
)
from flowrun.envs import TestEnv
from flowrun.networks import RingNetwork


class FlowIDM(BaseController):
    """IDM written as a Flow user would: per vehicle, from ``env.k.vehicle`` getters."""

    def __init__(
        self, veh_id: str, car_following_params: Any, v0: float = 30, T: float = 1,
        a: float = 1, b: float = 1.5, delta: float = 4, s0: float = 2, noise: float = 0,
    ) -> None:  # fmt: skip
        BaseController.__init__(self, veh_id, car_following_params, delay=0.0, noise=noise)
        self.v0, self.T, self.a, self.b, self.delta, self.s0 = v0, T, a, b, delta, s0

    def get_accel(self, env: Any) -> float:  # type: ignore[override]  # Flow's form
        vk = env.k.vehicle
        v = vk.get_speed(self.veh_id)
        lead = vk.get_leader(self.veh_id)
        h = vk.get_headway(self.veh_id)
        s_star = 0.0
        if lead:
            dv = v - vk.get_speed(lead)
            s_star = self.s0 + max(0, v * self.T + v * dv / (2 * np.sqrt(self.a * self.b)))
        return float(self.a * (1 - (v / self.v0) ** self.delta - (s_star / h) ** 2))


class Constant(BaseController):
    """Asks for the same acceleration every step (``None``: leave the car to SUMO)."""

    def __init__(self, veh_id: str, car_following_params: Any, accel: float | None = 1.0,
                 fail_safe: Any = None, noise: float = 0) -> None:  # fmt: skip
        super().__init__(veh_id, car_following_params, fail_safe=fail_safe, noise=noise)
        self.accel = accel

    def get_accel(self, env: Any) -> float | None:  # type: ignore[override]
        return self.accel


def ring_env(
    ctrl: tuple[Any, dict[str, Any]], n: int = 22, length: float = 230, lanes: int = 1,
    router: Any = (ContinuousRouter, {}), lane_changer: Any = None,
    cf: SumoCarFollowingParams | None = None, lc: SumoLaneChangeParams | None = None,
    lanes_distribution: float = float("inf"),
) -> TestEnv:  # fmt: skip
    vehicles = VehicleParams()
    vehicles.add(
        "u", acceleration_controller=ctrl, routing_controller=router,
        lane_change_controller=lane_changer, num_vehicles=n,
        car_following_params=cf or SumoCarFollowingParams(),
        lane_change_params=lc or SumoLaneChangeParams(),
    )  # fmt: skip
    net = NetParams(additional_params={"length": length, "lanes": lanes, "speed_limit": 30,
                                       "resolution": 40})  # fmt: skip
    initial = InitialConfig(bunching=20, lanes_distribution=lanes_distribution)
    network = RingNetwork("ring", vehicles, net, initial)
    return TestEnv(EnvParams(horizon=10_000), SumoParams(sim_step=0.1), network)


def speeds(env: TestEnv, steps: int, seed: int = 0) -> np.ndarray:
    env.reset(seed=seed)
    out = []
    for _ in range(steps):
        env.step(None)
        out.append([env.k.vehicle.get_speed(v) for v in sorted(env.k.vehicle.get_ids())])
    return np.array(out)


def test_flow_style_idm_drives_like_the_builtin_idm() -> None:
    runs = []
    ctrls: list[tuple[Any, dict[str, Any]]] = [(FlowIDM, {}), (IDMController, {})]
    for ctrl in ctrls:
        env = ring_env(ctrl)
        try:
            runs.append(speeds(env, 150))
        finally:
            env.close()
    assert runs[0][-1].mean() > 1.0  # the cars did start
    np.testing.assert_allclose(runs[0], runs[1], rtol=0, atol=1e-9)


def test_each_vehicle_gets_its_own_object_made_with_flows_constructor() -> None:
    cf = SumoCarFollowingParams(accel=1.5, decel=3.0)
    env = ring_env((Constant, {"accel": 0.5}), n=4, cf=cf)
    try:
        env.reset(seed=0)
        env.step(None)
        a = env.k.vehicle.get_acc_controller("u_1")
        assert isinstance(a, Constant)
        assert a.veh_id == "u_1" and a.accel == 0.5
        assert (a.max_accel, a.max_deaccel) == (1.5, 3.0)
        assert env.k.vehicle.get_acc_controller("u_1") is a
        assert env.k.vehicle.get_acc_controller("u_2") is not a
        assert isinstance(env.controls[0].controller, PerVehicleGroup)
        # memory per vehicle and no vectorised formula: the numpy ring backend refuses it
        assert env.controls[0].controller.stateful
    finally:
        env.close()


def test_accelerations_are_applied_and_none_leaves_the_car_to_sumo() -> None:
    env = ring_env((Constant, {"accel": 0.5}), n=4)
    try:
        v = speeds(env, 10)
        np.testing.assert_allclose(v[-1], 0.5, atol=1e-9)  # 10 steps of 0.5 m/s^2 * 0.1 s
    finally:
        env.close()
    env = ring_env((Constant, {"accel": None}), n=4)
    try:
        v = speeds(env, 10)
        # SUMO's own Krauss driver (accel 2.6 m/s^2 by default) speeds up faster
        assert np.all(v[-1] > 1.0)
    finally:
        env.close()


def test_fail_safe_clips_to_the_vehicle_type_accel() -> None:
    cf = SumoCarFollowingParams(accel=1.0, decel=1.0)
    env = ring_env((Constant, {"accel": 5.0, "fail_safe": "feasible_accel"}), n=4, cf=cf)
    try:
        v = speeds(env, 10)
        np.testing.assert_allclose(v[-1], 1.0, atol=1e-9)  # capped at 1 m/s^2, not 5
    finally:
        env.close()


def test_noise_is_seeded() -> None:
    runs = []
    for noise, seed in ((0.5, 3), (0.5, 3), (0.5, 4), (0.0, 3)):
        env = ring_env((Constant, {"accel": 0.5, "noise": noise}), n=4)
        try:
            runs.append(speeds(env, 20, seed))
        finally:
            env.close()
    np.testing.assert_array_equal(runs[0], runs[1])
    assert not np.allclose(runs[0], runs[2])
    assert not np.allclose(runs[0], runs[3])


class KeepCircling(BaseRouter):
    """Flow's continuous routing written as a user router: on its route's last edge a car
    takes the route that starts there."""

    calls = 0

    def choose_route(self, env: Any) -> list[str] | None:  # type: ignore[override]
        KeepCircling.calls += 1
        edge = env.k.vehicle.get_edge(self.veh_id)
        route = env.k.vehicle.get_route(self.veh_id)
        if route and edge == route[-1]:
            return list(env.available_routes[edge][0][0])
        return None


def test_flow_style_router_keeps_cars_on_the_ring() -> None:
    KeepCircling.calls = 0
    # 12 m/s for 30 s: 360 m, more than the 230 m route each car starts with
    env = ring_env((Constant, {"accel": None}), n=4, router=(KeepCircling, {}),
                   cf=SumoCarFollowingParams(max_speed=12))  # fmt: skip
    try:
        speeds(env, 300)
        assert len(env.k.vehicle.get_ids()) == 4
        assert KeepCircling.calls == 4 * 300
        # every car got a second lap appended on its first route's last edge
        assert all(len(env.k.vehicle.get_route(v)) > 4 for v in env.k.vehicle.get_ids())
        assert isinstance(env.k.vehicle.get_routing_controller("u_0"), KeepCircling)
        assert env.k.vehicle.get_routing_controller("u_3").veh_id == "u_3"
        own = env.k.vehicle.controllers.routing(0, "u_2")
        assert isinstance(own, KeepCircling) and own.veh_id == "u_2"
        assert own is env.k.vehicle.controllers.routing(0, "u_2")
    finally:
        env.close()


class GoLeft(BaseLaneChangeController):
    """Every car asks for the lane on its left."""

    def get_lane_change_action(self, env: Any) -> int:
        return 1


def test_flow_style_lane_changer_moves_cars_left() -> None:
    env = ring_env((FlowIDM, {}), n=4, lanes=2, lane_changer=(GoLeft, {}),
                   lc=SumoLaneChangeParams(lane_change_mode="no_lc_safe"),
                   lanes_distribution=1)  # fmt: skip
    try:
        env.reset(seed=0)
        assert [env.k.vehicle.get_lane(v) for v in env.k.vehicle.get_ids()] == [0] * 4
        for _ in range(30):
            env.step(None)
        assert [env.k.vehicle.get_lane(v) for v in env.k.vehicle.get_ids()] == [1] * 4
        assert sorted(env.k.vehicle.get_controlled_lc_ids()) == [f"u_{i}" for i in range(4)]
        own = env.k.vehicle.controllers.lane_changing(0, "u_1")  # the vehicle's own object
        assert isinstance(own, GoLeft) and own.veh_id == "u_1"
        assert env.k.vehicle.get_lane_changing_controller("u_1") is own
    finally:
        env.close()


def test_builtin_controller_answers_flows_get_action() -> None:
    env = ring_env((IDMController, {}), n=4)
    try:
        env.reset(seed=0)
        idm = IDMController("u_0", car_following_params=SumoCarFollowingParams())
        view = env.k.vehicle.get_acc_controller("u_0")
        assert idm.get_action(env) == pytest.approx(view.get_action(env))
        assert not IDMController.per_vehicle and FlowIDM.per_vehicle
    finally:
        env.close()


def test_flows_fail_safe_helpers_answer_for_the_vehicle() -> None:
    cf = SumoCarFollowingParams(accel=1.5, decel=2.0)
    env = ring_env((Constant, {"accel": 0.5}), n=4, cf=cf)
    try:
        speeds(env, 20)
        c = env.k.vehicle.get_acc_controller("u_0")
        vk = env.k.vehicle
        v, h = vk.get_speed("u_0"), vk.get_headway("u_0")
        leader = vk.get_leader("u_0")
        assert leader is not None
        v_lead = vk.get_speed(leader)
        assert c.safe_velocity(env) == pytest.approx(2 * h / 0.1 + v_lead - v)
        assert c.get_feasible_action(10.0) == 1.5
        assert c.get_feasible_action(-10.0) == -2.0
        assert c.get_safe_velocity_action(env, 0.2) == pytest.approx(0.2)  # far from unsafe
        # above the lane's 30 m/s limit within one step: capped to reach it exactly
        assert c.get_obey_speed_limit_action(env, 400.0) == pytest.approx((30 - v) / 0.1)
    finally:
        env.close()


def test_flow_style_idm_on_the_open_merge_matches_the_builtin() -> None:
    from flowrun.core.params import InFlows
    from flowrun.networks import MergeNetwork

    def run(ctrl: tuple[Any, dict[str, Any]]) -> dict[str, float]:
        vehicles = VehicleParams()
        vehicles.add("human", acceleration_controller=ctrl,
                     car_following_params=SumoCarFollowingParams(speed_mode="obey_safe_speed"))
        inflows = InFlows()
        inflows.add("inflow_highway", "human", vehs_per_hour=2000, depart_speed=10)
        inflows.add("inflow_merge", "human", vehs_per_hour=300, depart_speed=7.5)
        net = MergeNetwork("merge", vehicles, NetParams(inflows=inflows))
        env = TestEnv(EnvParams(horizon=10**9), SumoParams(sim_step=0.2, seed=3), net)
        try:
            env.reset(seed=3)
            for _ in range(300):  # 60 s: cars enter, merge and leave
                env.step(None)
            vk = env.k.vehicle
            return {v: vk.get_speed(v) for v in vk.get_ids()}
        finally:
            env.close()

    flow_style, builtin = run((FlowIDM, {})), run((IDMController, {}))
    assert len(flow_style) > 5 and set(flow_style) == set(builtin)
    assert all(flow_style[v] == pytest.approx(builtin[v], abs=1e-9) for v in builtin)
