"""Flow's template dict ``{net, rou, vtype}``: the vtype file's vTypes become vehicle types with
Flow's parameters and modes, the rou file's vehicles are added at each reset and driven by their
type (real SUMO for the runs). The XML files are written here; the road is the toy merge."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flowrun.config.params import ControllerSpec, EnvParams, NetParams, SumoParams, VehicleParams
from flowrun.errors import ConfigError
from flowrun.loading import config_from_dict
from flowrun.networks.base import Network, TemplateVehicle
from flowrun.networks.build import build_network
from tests.test_open_kernel import Drive, ToyMerge

VTYPES = """<additional>
  <vType id="slow" accel="0.8" decel="3.1" sigma="0.0" minGap="1.5" maxSpeed="12"
         speedDev="0.05" tau="2.0" length="12" carFollowModel="Krauss" lcStrategic="3"/>
  <vType id="fast" accel="2.0" decel="4.0" sigma="0.5" minGap="2.0" maxSpeed="25"
         speedDev="0.1"/>
</additional>
"""
ROUTES = """<routes>
  <vType id="slow" accel="9" decel="9" sigma="0" minGap="9" maxSpeed="9" speedDev="0"/>
  <route id="r_ramp" edges="ramp ce out"/>
  <vehicle id="s0" type="slow" depart="1.0" departPos="10" departSpeed="5">
    <route edges="hw ce out"/>
  </vehicle>
  <vehicle id="f0" type="fast" depart="0" route="r_ramp"/>
  <vehicle id="d0" depart="0" departPos="50"><route edges="out"/></vehicle>
  <flow id="fl" type="fast" route="r_ramp" begin="5" end="100" period="50"/>
</routes>
"""


@pytest.fixture(scope="module")
def net_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("net")
    return build_network(ToyMerge("toy", VehicleParams(), NetParams()).spec, out, name="toy")


def write(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def template(net_file: Path, tmp_path: Path, rou: str = ROUTES, vtype: str = VTYPES) -> dict:
    return {"net": str(net_file), "rou": write(tmp_path, "t.rou.xml", rou),
            "vtype": write(tmp_path, "t.add.xml", vtype)}  # fmt: skip


def test_each_vtype_is_a_vehicle_type_with_flows_six_attributes_and_modes(
    net_file: Path, tmp_path: Path
) -> None:
    net = Network("t", VehicleParams(), NetParams(template=template(net_file, tmp_path)))
    assert net.vehicles.type_names == ["slow", "fast"]
    assert net.vehicles.num_vehicles == 0
    slow = net.vehicles.type_parameters["slow"]
    cf, lc = slow["car_following_params"], slow["lane_change_params"]
    # accel, decel, sigma, minGap, maxSpeed, speedDev from the file; tau, speedFactor,
    # impatience, carFollowModel (and length, lc*) stay Flow's defaults, as in Flow
    assert dict(cf.controller_params) == {
        "accel": 0.8, "decel": 3.1, "sigma": 0.0, "tau": 1.0, "minGap": 1.5, "maxSpeed": 12.0,
        "speedFactor": 1.0, "speedDev": 0.05, "impatience": 0.5, "carFollowModel": "IDM",
    }  # fmt: skip
    assert cf.speed_mode == 31 and cf.length == 5.0
    assert dict(lc.controller_params) == {
        "laneChangeModel": "LC2013", "lcStrategic": "1.0", "lcCooperative": "1.0",
        "lcSpeedGain": "1.0", "lcKeepRight": "1.0",
    }  # fmt: skip
    assert lc.lane_change_mode == 1621
    assert slow["acceleration_controller"][0].__name__ == "SimCarFollowingController"
    assert slow["lane_change_controller"][0].__name__ == "SimLaneChangeController"


def test_the_rou_files_vehicles_and_routes_are_read(net_file: Path, tmp_path: Path) -> None:
    net = Network("t", VehicleParams(), NetParams(template=template(net_file, tmp_path)))
    assert net.routes == {
        "r_ramp": ["ramp", "ce", "out"], "s0": ["hw", "ce", "out"], "d0": ["out"]
    }  # fmt: skip
    assert net.spec.departures == (
        TemplateVehicle("s0", "slow", ("hw", "ce", "out"), 1.0, "10", "5"),
        TemplateVehicle("f0", "fast", ("ramp", "ce", "out"), 0.0, "base", "0"),
        TemplateVehicle("d0", "DEFAULT_VEHTYPE", ("out",), 0.0, "50", "0"),  # SUMO's defaults
    )


def test_only_vtypes_inside_distributions_count_when_there_are_any(
    net_file: Path, tmp_path: Path
) -> None:
    vtype = ('<additional><vType id="alone" accel="1" decel="1" sigma="0" minGap="1" '
             'maxSpeed="9" speedDev="0"/><vTypeDistribution id="mix"><vType id="fast" '
             'accel="2" decel="4" sigma="0.5" minGap="2" maxSpeed="25" speedDev="0.1"/>'
             '</vTypeDistribution></additional>')  # fmt: skip
    rou = '<routes><vehicle id="f0" type="fast" depart="0"><route edges="hw"/></vehicle></routes>'
    net = Network(
        "t", VehicleParams(), NetParams(template=template(net_file, tmp_path, rou, vtype))
    )
    assert net.vehicles.type_names == ["fast"]


def test_a_users_vehicle_type_of_the_same_id_keeps_its_settings(
    net_file: Path, tmp_path: Path
) -> None:
    mine = VehicleParams()
    mine.add("slow", acceleration_controller=ControllerSpec("IDM", {"noise": 0.0}))
    net = Network("t", mine, NetParams(template=template(net_file, tmp_path)))
    assert net.vehicles.type_names == ["slow", "fast"]
    assert net.vehicles.type_parameters["slow"]["acceleration_controller"][0].__name__ == (
        "IDMController"
    )
    assert net.vehicles.type_parameters["slow"]["car_following_params"].decel == 7.5
    assert mine.type_names == ["slow"]  # the user's object is not changed


@pytest.mark.parametrize(
    ("rou", "vtype", "message"),
    [
        (ROUTES, "<additional><vType id=", r"cannot read vtype file .*t\.add\.xml.* as XML"),
        (ROUTES, '<additional><vType accel="1"/></additional>', "vType number 1 .* has no id"),
        (ROUTES, '<additional><vType id="slow" accel="1"/></additional>',
         "vType 'slow' .* has no decel; Flow reads accel, decel"),
        ('<routes><vehicle id="b0" type="bus" depart="0"><route edges="hw"/></vehicle></routes>',
         VTYPES, "vehicle 'b0' is of type 'bus', which neither the vtype file nor the vehicles"),
        ('<routes><vehicle id="s0" type="slow" depart="0"><route edges="hw nowhere"/>'
         "</vehicle></routes>", VTYPES, "drives on 'nowhere', which the network has not"),
        ('<routes><vehicle id="s0" type="slow" depart="triggered"><route edges="hw"/>'
         "</vehicle></routes>", VTYPES, "depart='triggered' is not a time in seconds"),
    ],
)  # fmt: skip
def test_bad_template_files_are_one_clear_config_error(
    net_file: Path, tmp_path: Path, rou: str, vtype: str, message: str
) -> None:
    with pytest.raises(ConfigError, match=message) as err:
        Network("t", VehicleParams(), NetParams(template=template(net_file, tmp_path, rou, vtype)))
    assert err.value.path.startswith("template.")


def first_seen(env: Drive, steps: int) -> dict[str, int]:
    """Step ``steps`` times; the step after which each vehicle was first on the road."""
    seen: dict[str, int] = {}
    for i in range(steps):
        env.step(None)
        for vid in env.k.vehicle.get_ids():
            seen.setdefault(vid, i + 1)
    return seen


@pytest.mark.sumo
def test_template_vehicles_depart_on_time_and_sumo_drives_them_with_their_type(
    net_file: Path, tmp_path: Path
) -> None:
    net = Network("t", VehicleParams(), NetParams(template=template(net_file, tmp_path)))
    env = Drive(EnvParams(horizon=10**6), SumoParams(sim_step=0.5, seed=0), net)
    try:
        for _ in range(2):  # added again at each reset
            env.reset(seed=0)
            vk, api = env.k.vehicle, env.k.vehicle.api.vehicle
            assert vk.get_ids() == []
            # depart 0 and 1.0 s after the reset: the 1st and 3rd steps of 0.5 s (Flow adds
            # the reset's two steps to the file's depart)
            assert first_seen(env, 5) == {"f0": 1, "d0": 1, "s0": 3}
            assert api.getDecel("f0") == 4.0 and api.getMaxSpeed("f0") == 25.0
            assert vk.get_type("s0") == "slow"
            assert (api.getDecel("s0"), api.getTau("s0"), api.getLength("s0")) == (3.1, 1.0, 5.0)
            assert api.getMinGap("s0") == 1.5 and api.getLaneID("s0") == "hw_0"
            assert api.getSpeedMode("s0") == 31 and api.getLaneChangeMode("s0") == 1621
            row = vk.table.row("s0")
            assert not vk.table.commanded[row] and np.isnan(vk.last_cmd[row])
            assert api.getRoute("s0") == ("hw", "ce", "out")
            assert not vk.table.commanded[vk.table.row("d0")]  # SUMO's own type: SUMO drives
            # the rou file's <flow> still reaches SUMO, its cars of the vtype file's type
            assert "fl.0" in first_seen(env, 6)
            assert api.getDecel("fl.0") == 4.0 and api.getSpeedMode("fl.0") == 31
    finally:
        env.close()


@pytest.mark.sumo
def test_a_users_controller_drives_the_template_vehicles_of_its_type(
    net_file: Path, tmp_path: Path
) -> None:
    mine = VehicleParams()
    mine.add("slow", acceleration_controller=ControllerSpec("IDM", {"noise": 0.0}))
    net = Network("t", mine, NetParams(template=template(net_file, tmp_path)))
    env = Drive(EnvParams(horizon=10**6), SumoParams(sim_step=0.5, seed=0), net)
    try:
        env.reset(seed=0)
        assert "s0" in first_seen(env, 4)
        vk = env.k.vehicle
        row = vk.table.row("s0")
        assert vk.table.commanded[row] and not np.isnan(vk.last_cmd[row])
        assert vk.api.vehicle.getSpeedMode("s0") == 0  # the user's type's mode
        assert vk.api.vehicle.getDecel("s0") == 7.5
    finally:
        env.close()


def test_a_yaml_inflow_may_use_a_vtype_of_the_template(net_file: Path, tmp_path: Path) -> None:
    files = template(net_file, tmp_path)
    data = {
        "name": "t",
        "network": {"type": "template", "template": files,
                    "inflows": [{"edge": "hw", "veh_type": "fast", "vehs_per_hour": 600}]},
        "vehicles": [],
    }  # fmt: skip
    assert config_from_dict(data).network.net_params.inflows.get()[0].veh_type == "fast"
    data["network"]["inflows"][0]["veh_type"] = "fats"  # type: ignore[index]
    with pytest.raises(
        ConfigError, match=r"no vehicle group 'fats' \(did you mean 'fast'\?\).*: slow, fast"
    ):
        config_from_dict(data)


@pytest.mark.sumo
def test_a_car_sumo_inserts_in_the_resets_first_step_joins_the_kernel(
    net_file: Path, tmp_path: Path
) -> None:
    rou = ROUTES.replace('begin="5"', 'begin="0"')  # its first car departs in the empty step
    net = Network("t", VehicleParams(), NetParams(template=template(net_file, tmp_path, rou)))
    env = Drive(EnvParams(horizon=10**6), SumoParams(sim_step=0.5, seed=0), net)
    try:
        env.reset(seed=0)
        vk = env.k.vehicle
        assert "fl.0" in vk.api.vehicle.getIDList()
        assert vk.get_ids() == ["fl.0"]  # on the road at reset, so in the kernel too
        assert vk.get_type("fl.0") == "fast" and vk.get_speed("fl.0") >= 0
        env.step(None)
        assert sorted(vk.get_ids()) == ["d0", "f0", "fl.0"]
    finally:
        env.close()


@pytest.mark.sumo
def test_a_templates_route_files_are_filtered_once_not_at_every_reset(
    net_file: Path, tmp_path: Path
) -> None:
    net = Network("t", VehicleParams(), NetParams(template=template(net_file, tmp_path)))
    env = Drive(EnvParams(horizon=10**6), SumoParams(sim_step=0.5, seed=0), net)
    try:
        env.reset(seed=0)
        (files,) = env.k._route_files.values()
        copies = [f for f in files if f.parent != tmp_path]  # the filtered copies
        assert copies and all(f.is_file() for f in copies)
        stamps = [f.stat().st_mtime_ns for f in copies]
        env.reset(seed=1)
        assert [f.stat().st_mtime_ns for f in copies] == stamps  # not written again
        assert env.k.vehicle.api.vehicle.getIDList() == ()  # the reset itself still worked
        assert first_seen(env, 3)["f0"] == 1
    finally:
        env.close()
