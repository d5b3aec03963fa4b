"""Controller parameters are declared once: the table, the constructor and the checks agree."""

from __future__ import annotations

import inspect

import pytest

from flowrun.controllers import (
    FollowerStopper,
    GippsController,
    IDMController,
    OVMController,
    build_controller,
)
from flowrun.controllers.params import ParameterValueError, parameters
from flowrun.controllers.registry import (
    controller_lines,
    controller_names,
    controller_parameters,
    resolve_controller,
)
from flowrun.errors import ConfigError

ACCELERATION = [resolve_controller(name) for name in controller_names("acceleration")]


@pytest.mark.parametrize("cls", ACCELERATION, ids=lambda c: c.__name__)
def test_the_table_is_the_constructor_signature(cls: type) -> None:
    signature = inspect.signature(cls).parameters
    table = parameters(cls)
    assert [p.name for p in table] == list(signature)
    assert [p.default for p in table] == [p.default for p in signature.values()]


def test_flow_positional_order_is_kept() -> None:
    idm = IDMController("human_0", 25, 1.5)
    assert (idm.veh_id, idm.v0, idm.T, idm.a) == ("human_0", 25.0, 1.5, 1.0)
    gipps = GippsController("g_0", None, 20)
    assert (gipps.v0, gipps.delay, gipps.time_delay) == (20.0, 0.0, 0.0)
    assert GippsController(delay=0.4).time_delay == 0.4


def test_checked_values_are_stored_as_floats() -> None:
    ctrl = build_controller("IDM", {"v0": 25, "delta": 4})
    assert isinstance(ctrl.v0, float) and isinstance(ctrl.delta, float)
    assert FollowerStopper(control_length=[1, 2]).control_length == (1.0, 2.0)
    assert FollowerStopper(danger_edges=["a", "a"]).danger_edges == frozenset({"a"})


def test_a_bound_named_after_another_parameter_uses_its_value() -> None:
    expected = r"OVMController: h_go must be a finite number > 4, got 3"
    with pytest.raises(ParameterValueError, match=expected):
        OVMController(h_st=4, h_go=3)
    with pytest.raises(ConfigError, match=r"dx_3_0 must be a finite number > 7") as err:
        build_controller("FollowerStopper", {"dx_2_0": 7, "dx_3_0": 6})
    assert err.value.path == "dx_3_0"


def test_gipps_deceleration_error_names_the_parameter() -> None:
    with pytest.raises(ConfigError, match="b_l must be a negative deceleration") as err:
        build_controller("Gipps", {"b_l": 0})
    assert err.value.path == "b_l"


def test_list_shows_every_parameter_with_default_unit_and_bounds() -> None:
    lines = controller_lines()
    at = lines.index("IDM  (IDMController, acceleration)")
    assert lines[at + 1] == "    v0 = 30 m/s, > 0: desired speed"
    assert "    h_go = 15 m, > h_st: gap above which it is v_max" in lines
    assert "    fail_safe = safe_velocity: fail-safe name(s) run on each command" in lines
    # Flow's per-vehicle arguments are not config parameters
    names = [p.name for p in controller_parameters(IDMController)]
    assert "veh_id" not in names and "car_following_params" not in names
    assert names[:6] == ["v0", "T", "a", "b", "delta", "s0"]
