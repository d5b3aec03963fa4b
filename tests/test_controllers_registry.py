"""Controller registry, fail-safes, routing and lane-change controllers (no SUMO)."""

from __future__ import annotations

import math
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from flowrun.controllers import (
    AccelerationController,
    BCMController,
    ContinuousRouter,
    IDMController,
    PISaturation,
    RLController,
    SimCarFollowingController,
    SimLaneChangeController,
    StaticLaneChanger,
    build_controller,
    controller_kind,
    controller_names,
    make_inputs,
    needs_new_route,
    resolve_controller,
)
from flowrun.controllers.fail_safe import check_fail_safe, instantaneous, safe_velocity
from flowrun.controllers.routing import pick_route
from flowrun.errors import ConfigError

INF = math.inf


# --- registry ------------------------------------------------------------------------------


def test_controller_names_by_kind() -> None:
    accel = controller_names("acceleration")
    assert accel[:3] == ["IDM", "OVM", "LinearOVM"]
    assert {"BCM", "BandoFTL", "Gipps", "LAC", "FollowerStopper", "PISaturation"} <= set(accel)
    assert {"RLController", "SimCarFollowingController"} <= set(accel)
    routers = ["ContinuousRouter", "GridRouter", "MinicityRouter", "I210Router"]
    assert controller_names("routing") == routers
    assert controller_names("lane_change") == ["SimLaneChangeController", "StaticLaneChanger"]
    assert controller_names() == [*accel, *routers, *controller_names("lane_change")]


def test_short_names_class_names_and_aliases_resolve_to_the_same_class() -> None:
    assert resolve_controller("IDM") is IDMController
    assert resolve_controller("IDMController") is IDMController
    assert resolve_controller("BCM") is BCMController
    assert resolve_controller("RL") is RLController
    assert resolve_controller("RLController") is RLController
    assert resolve_controller("SimCarFollowingController") is SimCarFollowingController
    assert resolve_controller("ContinuousRouter", kind="routing") is ContinuousRouter
    for name in controller_names():
        cls = resolve_controller(name)
        assert cls.registered_name == name
        assert resolve_controller(cls.__name__) is cls


def test_controller_kind() -> None:
    assert controller_kind(IDMController) == "acceleration"
    assert controller_kind(ContinuousRouter) == "routing"
    assert controller_kind(StaticLaneChanger) == "lane_change"
    with pytest.raises(ConfigError, match="not a controller"):
        controller_kind(dict)


def test_typo_gets_a_did_you_mean() -> None:
    with pytest.raises(ConfigError, match=r"did you mean 'IDM'\?") as err:
        resolve_controller("IDN")
    assert "import path" in str(err.value)
    with pytest.raises(ConfigError, match=r"did you mean 'IDMController'\?"):
        resolve_controller("IDMControler")
    with pytest.raises(ConfigError, match=r"did you mean 'ContinuousRouter'\?"):
        resolve_controller("ContinousRouter", kind="routing")


def test_wrong_kind_is_refused() -> None:
    with pytest.raises(
        ConfigError, match="is a routing controller, but an acceleration controller"
    ):
        resolve_controller("ContinuousRouter", kind="acceleration")


@pytest.fixture
def user_module(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    name = "flowrun_test_user_ctrl"
    (tmp_path / f"{name}.py").write_text(
        "import numpy as np\n"
        "from flowrun.controllers import AccelerationController\n\n"
        "class ConstantAccel(AccelerationController):\n"
        "    def __init__(self, value: float = 0.5, noise: float = 0.0) -> None:\n"
        "        super().__init__(noise=noise)\n"
        "        self.value = value\n\n"
        "    def _accel(self, inputs):\n"
        "        return np.full(inputs.size, self.value)\n\n"
        "class NotAController:\n"
        "    pass\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    yield name
    sys.modules.pop(name, None)


def test_import_path_loads_a_user_controller(user_module: str) -> None:
    cls = resolve_controller(f"{user_module}:ConstantAccel", kind="acceleration")
    assert cls.__name__ == "ConstantAccel"
    ctrl = build_controller(f"{user_module}:ConstantAccel", {"value": 1.25})
    out = ctrl.get_accel(make_inputs([1.0, 2.0], [5.0, 6.0]), np.random.default_rng(0))
    assert out == pytest.approx([1.25, 1.25])


def test_import_path_errors_are_config_errors(user_module: str) -> None:
    with pytest.raises(ConfigError, match=r"did you mean 'ConstantAccel'\?"):
        resolve_controller(f"{user_module}:ConstantAcel")
    with pytest.raises(ConfigError, match="not a controller"):
        resolve_controller(f"{user_module}:NotAController")
    with pytest.raises(ConfigError, match="cannot import module 'no_such_module_xyz'"):
        resolve_controller("no_such_module_xyz:Foo")
    with pytest.raises(ConfigError, match=r"expected 'package\.module:Class'"):
        resolve_controller(":Foo")


def test_build_controller_passes_parameters() -> None:
    ctrl = build_controller("IDM", {"v0": 25, "T": 1.5, "noise": 0.1})
    assert isinstance(ctrl, IDMController)
    assert (ctrl.v0, ctrl.T, ctrl.noise) == (25.0, 1.5, 0.1)
    assert isinstance(build_controller("RLController", {}), RLController)
    assert isinstance(build_controller("ContinuousRouter"), ContinuousRouter)


def test_build_controller_unknown_parameter_has_did_you_mean() -> None:
    with pytest.raises(ConfigError, match=r"unknown parameter 'v00' for IDMController.*'v0'") as e:
        build_controller("IDM", {"v00": 25})
    assert e.value.path == "v00"
    with pytest.raises(ConfigError, match=r"unknown parameter 'noise'.*no parameters"):
        build_controller("RLController", {"noise": 0.1})


@pytest.mark.parametrize(
    ("params", "fragment"),
    [
        ({"v0": -1}, "v0 must be a finite number > 0"),
        ({"T": -0.5}, "T must be a finite number >= 0"),
        ({"v0": "fast"}, "got 'fast'"),
        ({"a": True}, "a must be"),
        ({"s0": math.nan}, "s0 must be"),
        ({"noise": -0.1}, "noise must be"),
        ({"fail_safe": "instantanous"}, "did you mean 'instantaneous'"),
        ({"fail_safe": True}, "fail_safe True is a bool; give a name or a list"),
    ],
)
def test_build_controller_bad_values_are_config_errors(params: dict, fragment: str) -> None:
    with pytest.raises(ConfigError, match="bad parameters for IDMController") as err:
        build_controller("IDM", params)
    assert fragment in err.value.message
    assert err.value.path == next(iter(params))
    assert isinstance(err.value, ValueError)  # what Flow raises for a bad value


def test_gipps_decelerations_must_be_negative() -> None:
    with pytest.raises(ConfigError, match="b must be a negative deceleration"):
        build_controller("Gipps", {"b": 1.0})


# --- fail-safes ----------------------------------------------------------------------------


def test_fail_safe_names_are_checked() -> None:
    assert check_fail_safe(None) == ()
    assert check_fail_safe("safe_velocity") == ("safe_velocity",)
    assert check_fail_safe(["instantaneous", "obey_speed_limit"]) == (
        "instantaneous",
        "obey_speed_limit",
    )
    with pytest.raises(ValueError, match="unknown fail_safe"):
        check_fail_safe(["feasible"])


def test_instantaneous_fail_safe_stops_when_too_close() -> None:
    # v=10, a=0, dt=0.1: v_next = 10; threshold = 0.1*10 + 1e-3*10 + 0.5*10*0.1 = 1.51 m
    # h=0.8 < 1.51 -> stop within one step: -10/0.1 = -100; h=2 and no leader -> keep 0
    v = np.array([10.0, 10.0, 10.0])
    h = np.array([0.8, 2.0, INF])
    assert instantaneous(np.zeros(3), v, h, 0.1) == pytest.approx([-100.0, 0.0, 0.0])


def test_instantaneous_fail_safe_via_controller() -> None:
    # CFM at v=10, h=1, v_lead=10: (1-1) + 0 + (8-10) = -2 -> v_next = 9.8 > 0,
    # threshold = 0.98 + 0.01 + 0.5 = 1.49 > 1 -> -100
    inp = make_inputs([10.0], [1.0], [10.0], dt=0.1)
    assert build_controller("CFM").get_accel(inp, np.random.default_rng(0)) == pytest.approx([-2])
    ctrl = build_controller("CFM", {"fail_safe": "instantaneous"})
    assert ctrl.get_accel(inp, np.random.default_rng(0)) == pytest.approx([-100.0])


def test_obey_speed_limit_fail_safe() -> None:
    # IDM free road at v=29.99 wants 1 - (29.99/30)^4 = 0.00133; with a limit of 29.99 m/s
    # the next speed may not exceed it: (29.99 - 29.99)/0.1 = 0
    ctrl = IDMController(fail_safe="obey_speed_limit")
    inp = make_inputs([29.99], [INF], speed_limit=29.99)
    assert IDMController().get_accel(inp, np.random.default_rng(0))[0] > 1e-3
    assert ctrl.get_accel(inp, np.random.default_rng(0)) == pytest.approx([0.0], abs=1e-12)


def test_safe_velocity_fail_safe() -> None:
    # v=5, v_lead=0, h=0.1, dt=0.1, delay 0: v_safe = 2*0.1/0.1 + (0 - 5) = -3 <= 0 -> -5/0.1
    # v=5, v_lead=5, h=2: v_safe = 2*2/0.1 + 0 = 40 -> keep 0.5; with a 4 s delay:
    # v_safe = 40 - 2*5*4 = 0 -> -50 (no leader: v_safe = inf -> keep 0.5)
    a = np.array([0.5, 0.5])
    v = np.array([5.0, 5.0])
    out = safe_velocity(a, v, np.array([0.1, 2.0]), np.array([0.0, 5.0]), 0.1, 0.0)
    assert out == pytest.approx([-50.0, 0.5])
    out = safe_velocity(a, v, np.array([2.0, INF]), np.array([5.0, 5.0]), 0.1, 4.0)
    assert out == pytest.approx([-50.0, 0.5])


def test_feasible_accel_clips_to_vehicle_limits() -> None:
    ctrl = IDMController(fail_safe="feasible_accel")
    inp = make_inputs([0.0, 10.0], [INF, 1.0], [0.0, 10.0], max_accel=0.5, max_decel=4.5)
    # free road from rest wants 1.0 -> 0.5; h=1 wants ~-143 -> -4.5
    assert ctrl.get_accel(inp, np.random.default_rng(0)) == pytest.approx([0.5, -4.5])


# --- routing and lane change ---------------------------------------------------------------


def test_continuous_router_flags_vehicles_on_their_last_edge() -> None:
    edges_left = np.array([3, 1, 0, 0, -1])
    assert needs_new_route(edges_left).tolist() == [False, False, True, True, True]
    assert ContinuousRouter().reroute_mask(edges_left).tolist() == [False, False, True, True, True]


def test_continuous_router_draws_routes_by_fraction_reproducibly() -> None:
    router = ContinuousRouter()
    choices = [(["top", "left"], 0.25), (["top", "right"], 0.75)]
    rng = np.random.default_rng(0)
    picks = [tuple(router.choose_route("top", choices, rng) or ()) for _ in range(4000)]
    share = picks.count(("top", "right")) / len(picks)
    assert share == pytest.approx(0.75, abs=0.03)
    rng2 = np.random.default_rng(0)
    again = [tuple(router.choose_route("top", choices, rng2) or ()) for _ in range(4000)]
    assert picks == again
    assert router.choose_route("top", [], rng) is None
    assert pick_route([(["a", "b"], 1.0)], rng) == ["a", "b"]


def test_lane_change_controllers() -> None:
    assert SimLaneChangeController().get_lane_change(3) is None
    assert not SimLaneChangeController.commands_sumo
    static = StaticLaneChanger().get_lane_change(3)
    assert static is not None and static.tolist() == [0, 0, 0]
    assert resolve_controller("StaticLaneChanger", kind="lane_change") is StaticLaneChanger


def test_stateful_flag() -> None:
    assert PISaturation.stateful
    assert not IDMController.stateful
    assert issubclass(PISaturation, AccelerationController)
