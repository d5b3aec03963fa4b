"""More of Flow's ``k.vehicle`` / ``k.network`` getters and ``flow.core.util`` helpers
(Flow's documented behaviour; real SUMO where a simulation is needed)."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from flowrun.core.util import EMISSION_CSV_COLUMNS, emission_to_csv, ensure_dir
from tests.test_open_kernel import make, on_network
from tests.test_ring_placement_flow import ring

# ----------------------------------------------------------------- k.network


def test_figure_eight_junction_list_is_its_internal_edges() -> None:
    env = on_network("figure_eight")
    env.reset(seed=0)
    try:
        junctions = env.k.network.get_junction_list()
        # one lane: two crossing links at the centre and one link at each ring end
        assert sorted(junctions) == sorted(
            [":bottom_0", ":top_0", ":right_0", ":left_0", ":center_0", ":center_1"]
        )
        assert not set(junctions) & set(env.k.network.get_edge_list())
    finally:
        env.close()


def test_figure_eight_internal_edge_by_junction_name_or_sumo_id() -> None:
    env = on_network("figure_eight")
    env.reset(seed=0)
    try:
        net = env.k.network
        # Flow's figure eight starts at the bottom ring-end link (x = 0); its first edge
        # "bottom" begins 0.28 m later
        assert net.get_x(":bottom", 0.1) == pytest.approx(0.1)
        assert net.get_x(":bottom_0", 0.1) == pytest.approx(0.1)
        assert net.get_x("bottom", 4.72) == pytest.approx(5.0)
        assert net.get_x("", 4.72) == -1001
        assert net.get_x(":nowhere", 1.0) == -1001
    finally:
        env.close()


def test_ring_has_no_junctions() -> None:
    from flowrun.kernel.network import NetworkKernel

    assert NetworkKernel(ring_spec()).get_junction_list() == []


def ring_spec():  # type: ignore[no-untyped-def]
    from flowrun.config.params import InitialConfig

    return ring(InitialConfig()).spec


# ----------------------------------------------------------------- k.vehicle


def test_initial_speed_is_the_groups_entry_speed() -> None:
    from flowrun.config.params import (
        ControllerSpec,
        EnvParams,
        InitialConfig,
        NetParams,
        SumoParams,
        VehicleParams,
    )
    from flowrun.networks.ring import RingNetwork
    from tests.test_open_kernel import Drive

    vehicles = VehicleParams()
    vehicles.add("slow", acceleration_controller=ControllerSpec("IDM", {}), num_vehicles=2,
                 initial_speed=3.0)  # fmt: skip
    vehicles.add("still", acceleration_controller=ControllerSpec("IDM", {}), num_vehicles=2)
    net = RingNetwork("ring", vehicles, NetParams(additional_params={"length": 230, "lanes": 1,
                      "speed_limit": 30, "resolution": 40}), InitialConfig())  # fmt: skip
    env = Drive(EnvParams(horizon=100), SumoParams(sim_step=0.1, seed=0), net)
    env.reset(seed=0)
    try:
        k = env.k.vehicle
        assert k.get_initial_speed("slow_0") == 3.0
        assert k.get_initial_speed("still_1") == 0.0
        assert k.get_initial_speed(["slow_1", "still_0"]) == [3.0, 0.0]
        assert k.get_initial_speed("nobody") == -1001
        assert k.get_initial_speed("nobody", error=None) is None
        # it is the entry speed, not the current one
        for _ in range(20):
            env.step(None)
        assert k.get_initial_speed("still_0") == 0.0
        assert k.get_speed("still_0") > 0.0
    finally:
        env.close()


def test_num_not_departed_counts_inflow_cars_waiting_for_room() -> None:
    # 7200 veh/h on the highway entry is more than its one lane takes at 10 m/s departures:
    # SUMO keeps the cars it could not insert yet as pending, Flow's "not departed"
    env = make(hw_vph=7200.0, ramp_vph=0.0)
    env.reset(seed=0)
    try:
        k = env.k.vehicle
        waiting = []
        for _ in range(300):
            env.step(None)
            waiting.append(k.get_num_not_departed())
        pending = len(env.k.vehicle.api.simulation.getPendingVehicles())
        assert waiting[-1] == pending
        assert max(waiting) > 0
        assert all(isinstance(w, int) and w >= 0 for w in waiting)
    finally:
        env.close()


def test_no_car_waits_when_the_inflow_fits() -> None:
    env = make(hw_vph=300.0, ramp_vph=0.0)
    env.reset(seed=0)
    try:
        for _ in range(100):
            env.step(None)
            assert env.k.vehicle.get_num_not_departed() == 0
    finally:
        env.close()


# ----------------------------------------------------------------- flow.core.util

EMISSION_XML = """<?xml version="1.0" encoding="UTF-8"?>
<emission-export>
    <timestep time="0.10">
        <vehicle id="b" eclass="HBEFA3/PC_G_EU4" CO2="2624.72" CO="164.78" HC="0.81"
            NOx="1.20" PMx="0.07" fuel="1128.65" electricity="0.00" noise="55.94"
            route="routebottom" type="human" waiting="0.00" lane="bottom_1" pos="5.10"
            speed="0.00" angle="90.00" x="-45.00" y="0.00"/>
        <vehicle id="a" eclass="HBEFA3/PC_G_EU4" CO2="2624.72" CO="164.78" HC="0.81"
            NOx="1.20" PMx="0.07" fuel="1128.65" electricity="0.00" noise="55.94"
            route="routetop" type="rl" waiting="0.00" lane=":center_0_0" pos="2.50"
            speed="1.50" angle="0.00" x="0.00" y="3.00"/>
    </timestep>
    <timestep time="0.20">
        <vehicle id="a" eclass="HBEFA3/PC_G_EU4" CO2="2624.72" CO="164.78" HC="0.81"
            NOx="1.20" PMx="0.07" fuel="1128.65" electricity="0.00" noise="55.94"
            route="routetop" type="rl" waiting="0.00" lane="top_0" pos="0.10"
            speed="1.60" angle="0.00" x="0.00" y="4.00"/>
        <vehicle id="c" type="human" lane="top_0"/>
    </timestep>
"""  # cut short, as when SUMO is stopped before closing the file


def _read(path: str) -> tuple[list[str], list[dict[str, str]]]:
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        return list(reader.fieldnames or []), list(reader)


def test_emission_to_csv_writes_flows_columns_next_to_the_xml(tmp_path: Path) -> None:
    xml = tmp_path / "ring-emission.xml"
    xml.write_text(EMISSION_XML + "</emission-export>\n")
    out = emission_to_csv(str(xml))
    assert out == str(tmp_path / "ring-emission.csv")
    headers, rows = _read(out)
    assert headers == list(EMISSION_CSV_COLUMNS)
    assert set(headers) == {
        "time", "CO", "y", "CO2", "electricity", "type", "id", "eclass", "waiting", "NOx",
        "fuel", "HC", "x", "route", "relative_position", "noise", "angle", "PMx", "speed",
        "edge_id", "lane_number",
    }  # fmt: skip
    # the incomplete record of "c" is skipped; rows are by vehicle id, then time
    assert [(r["id"], float(r["time"])) for r in rows] == [("a", 0.1), ("a", 0.2), ("b", 0.1)]
    a0 = rows[0]
    assert (a0["edge_id"], a0["lane_number"]) == (":center_0", "0")
    assert float(a0["relative_position"]) == 2.5 and float(a0["speed"]) == 1.5
    assert (rows[2]["edge_id"], rows[2]["lane_number"]) == ("bottom", "1")


def test_emission_to_csv_reads_a_file_cut_short_and_takes_an_output_path(
    tmp_path: Path,
) -> None:
    xml = tmp_path / "cut-emission.xml"
    xml.write_text(EMISSION_XML)
    out = tmp_path / "elsewhere.csv"
    assert emission_to_csv(str(xml), str(out)) == str(out)
    _, rows = _read(str(out))
    assert len(rows) == 3


def test_ensure_dir_creates_and_returns_the_path(tmp_path: Path) -> None:
    target = tmp_path / "a" / "b"
    assert ensure_dir(str(target)) == str(target)
    assert target.is_dir()
    assert ensure_dir(str(target)) == str(target)  # already there: fine
