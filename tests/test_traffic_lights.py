"""Signal programs (Flow's TrafficLightParams) and ``k.traffic_light`` on real SUMO.

SUMO tests use a small 2x2 grid (1 s steps, seeded) and read every state back from SUMO.
"""

from __future__ import annotations

import itertools
from typing import Any

import pytest

from flowrun.config.params import (
    EnvParams,
    InFlows,
    NetParams,
    SumoCarFollowingParams,
    SumoParams,
    TrafficLightParams,
    VehicleParams,
)
from flowrun.config.traffic_lights import DETECTOR_GAP, MAX_GAP, parse_phase
from flowrun.controllers import GridRouter
from flowrun.envs.test import TestEnv
from flowrun.errors import ConfigError
from flowrun.networks.tls import NetLight, resolve_programs, tls_additional_xml
from flowrun.networks.traffic_light_grid import TrafficLightGridNetwork

PHASES = [
    {"duration": 7, "state": "GrGr"},
    {"duration": 3, "state": "yryr"},
    {"duration": 5, "state": "rGrG"},
    {"duration": 2, "state": "ryry"},
]
LIGHTS = {f"center{i}": NetLight(f"center{i}", 4, ()) for i in range(4)}


# ---------------------------------------------------------------- params, no SUMO
def test_add_keeps_flows_defaults_and_names() -> None:
    tl = TrafficLightParams()
    tl.add("center0")
    tl.add("center1", tls_type="actuated", phases=PHASES)
    props = tl.get_properties()
    assert props["center0"] == {"id": "center0", "type": "static", "programID": 10}
    assert props["center1"]["max-gap"] == MAX_GAP == 3.0
    assert props["center1"]["detector-gap"] == DETECTOR_GAP == 0.6
    assert props["center1"]["show-detectors"] is True
    assert "max-gap" not in props["center0"]


def test_actuated_default_is_flows_four_phase_program() -> None:
    d = TrafficLightParams().actuated_default()
    assert [p["state"] for p in d["phases"]] == ["GrGr", "yryr", "rGrG", "ryry"]
    assert [p["duration"] for p in d["phases"]] == ["31", "6", "31", "6"]
    assert (d["phases"][0]["minDur"], d["phases"][0]["maxDur"]) == ("8", "45")
    assert (d["tl_type"], d["program_id"], d["max_gap"], d["detector_gap"]) == (
        "actuated", "1", "3.0", "0.8")  # fmt: skip


def test_baseline_gives_every_light_the_actuated_default_unless_added() -> None:
    tl = TrafficLightParams(baseline=True)
    tl.add("center2", phases=PHASES)
    programs = {p.node_id: p for p in resolve_programs(tl, LIGHTS)}
    assert set(programs) == set(LIGHTS)
    assert programs["center0"].tls_type == "actuated"
    assert programs["center0"].phases[0].min_dur == 8.0
    assert programs["center2"].tls_type == "static"
    assert programs["center2"].program_id == "10"


@pytest.mark.parametrize(
    ("phase", "path", "words"),
    [
        ({"duration": 5, "state": "GrXr"}, "phases[0].state", "unknown signal character"),
        ({"duration": 0, "state": "GrGr"}, "phases[0].duration", "> 0"),
        ({"state": "GrGr"}, "phases[0]", "needs 'duration'"),
        ({"duration": 5, "state": "GrGr", "minDuration": 3}, "phases[0].minDuration", "minDur"),
    ],
)
def test_bad_phases_are_config_errors_naming_the_key(
    phase: dict[str, Any], path: str, words: str
) -> None:
    with pytest.raises(ConfigError, match=words) as err:
        TrafficLightParams().add("center0", phases=[phase])
    assert err.value.path == f"traffic_lights.center0.{path}"


def test_unknown_tls_type_suggests_the_close_one() -> None:
    with pytest.raises(ConfigError, match="did you mean 'actuated'"):
        TrafficLightParams().add("center0", tls_type="actuatd")


def test_a_state_shorter_than_the_junctions_links_is_an_error() -> None:
    tl = TrafficLightParams()
    tl.add("center1", phases=[{"duration": 5, "state": "GrG"}])
    with pytest.raises(ConfigError, match="3 characters but junction 'center1' controls 4") as e:
        resolve_programs(tl, LIGHTS)
    assert e.value.path == "traffic_lights.center1.phases[0].state"


def test_longer_states_run_cut_to_the_links_with_one_warning(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """As SUMO runs them (Flow's grid example gives 12-character states to 4-link lights)."""
    tl = TrafficLightParams()
    tl.add("center1", phases=[{"duration": 31, "state": "GrGrGrGrGrGr"},
                              {"duration": 6, "state": "yryryryryryr"}])  # fmt: skip
    with caplog.at_level("WARNING", logger="flowrun.networks.tls"):
        (program,) = resolve_programs(tl, LIGHTS, warn=True)
    assert [p.state for p in program.phases] == ["GrGr", "yryr"]
    (record,) = caplog.records
    assert "'center1' controls 4 links" in record.getMessage()
    assert "'GrGrGrGr', 'yryryryr'" in record.getMessage()
    caplog.clear()
    resolve_programs(tl, LIGHTS)  # when the kernel writes the file: no second warning
    assert not caplog.records


def test_light_on_a_node_without_one_is_an_error_with_a_suggestion() -> None:
    tl = TrafficLightParams()
    tl.add("centre1", phases=PHASES)
    with pytest.raises(ConfigError, match=r"no traffic-light junction 'centre1'.*center1"):
        resolve_programs(tl, LIGHTS)


def test_tlLogic_xml_has_phases_and_actuated_params() -> None:
    tl = TrafficLightParams()
    tl.add("center0", tls_type="actuated", offset=4, phases=[
        {"duration": 31, "minDur": 8, "maxDur": 45, "state": "GrGr"},
        {"duration": 6, "state": "yryr"}])  # fmt: skip
    xml = tls_additional_xml(resolve_programs(tl, LIGHTS))
    assert '<tlLogic id="center0" type="actuated" programID="10" offset="4.0">' in xml
    assert '<param key="max-gap" value="3.0"/>' in xml
    assert '<phase duration="31.0" state="GrGr" minDur="8.0" maxDur="45.0"/>' in xml


def test_phase_parser_accepts_flows_string_numbers() -> None:
    phase = parse_phase({"duration": "31", "minDur": "8", "maxDur": "45", "state": "GrGr"}, "p")
    assert (phase.duration, phase.min_dur, phase.max_dur) == (31.0, 8.0, 45.0)


def test_grid_router_keeps_every_route() -> None:
    import numpy as np

    router = GridRouter()
    assert not router.reroute_mask(np.array([0, 1, 3])).any()
    assert router.choose_route("bot0_2", [(["bot0_2"], 1.0)], np.random.default_rng(0)) is None


# ---------------------------------------------------------------- SUMO
def grid_env(tl: TrafficLightParams, vph: float = 600.0, seed: int = 1) -> TestEnv:
    vehicles = VehicleParams()
    # Flow's grid benchmarks: SUMO drives, obeying right of way and the lights
    vehicles.add(
        "human",
        num_vehicles=0,
        car_following_params=SumoCarFollowingParams(speed_mode="right_of_way"),
    )
    inflows = InFlows()
    for edge in ("bot0_0", "bot1_0", "top0_2", "right0_0", "left2_1"):
        inflows.add(edge, "human", vehs_per_hour=vph, depart_lane="free", depart_speed=10)
    grid = {"row_num": 2, "col_num": 2, "inner_length": 150, "short_length": 150,
            "long_length": 60}  # fmt: skip
    net = TrafficLightGridNetwork(
        "grid", vehicles, NetParams(inflows=inflows, additional_params={"grid_array": grid}),
        traffic_lights=tl,
    )  # fmt: skip
    return TestEnv(EnvParams(horizon=10**6), SumoParams(sim_step=1.0, seed=seed), net)


@pytest.mark.sumo
def test_static_program_switches_exactly_at_its_durations() -> None:
    tl = TrafficLightParams()
    tl.add("center0", phases=PHASES, offset=0)
    env = grid_env(tl)
    try:
        env.reset(seed=0)
        k = env.k.traffic_light
        api = env.k.vehicle.api.trafficlight
        assert k.get_ids() == ["center0", "center1", "center2", "center3"]
        assert k.get_program("center0") == "10"
        assert k.get_program("center1") == "0"  # SUMO's default program where none was added
        changes: list[tuple[float, str]] = []
        last = k.get_state("center0")
        for _ in range(60):
            env.step(None)
            state = k.get_state("center0")
            assert state == api.getRedYellowGreenState("center0")  # snapshot == SUMO
            assert k.get_phase("center0") == api.getPhase("center0")
            if state != last:
                changes.append((k.time, state))
                last = state
        times = [t for t, _ in changes]
        gaps = [b - a for a, b in itertools.pairwise(times)]
        cycle = [7.0, 3.0, 5.0, 2.0]
        order = [s for _, s in changes[:4]]
        first = ["GrGr", "yryr", "rGrG", "ryry"].index(order[0])
        expected = (cycle[first:] + cycle[:first]) * 4
        # the gap after entering state s is the duration of s
        assert len(gaps) >= 10
        assert gaps == expected[: len(gaps)]
        assert k.get_time_to_switch("center0") == pytest.approx(
            api.getNextSwitch("center0") - env.k.simulation.time
        )
    finally:
        env.close()


@pytest.mark.sumo
def test_set_state_overrides_the_program_and_is_read_back() -> None:
    env = grid_env(TrafficLightParams())
    try:
        env.reset(seed=0)
        k = env.k.traffic_light
        k.set_state("center3", "rGrG")
        assert k.get_state("center3") == "rGrG"
        env.step(None)
        assert k.get_state("center3") == "rGrG"
        assert k.get_program("center3") == "online"
        k.set_state("center3", "y", link_index=1)
        env.step(None)
        assert k.get_state("center3") == "ryrG"
        with pytest.raises(ValueError, match="controls 4 links"):
            k.set_state("center3", "GrG")
        with pytest.raises(KeyError, match="did you mean 'center3'"):
            k.get_state("centre3")
        assert k.get_controlled_lanes("center0") == ["left1_0_0", "top0_1_0", "right0_0_0",
                                                     "bot0_0_0"]  # fmt: skip
    finally:
        env.close()


@pytest.mark.sumo
def test_set_state_before_reset_waits_for_the_start_and_a_longer_state_is_cut(
    caplog: pytest.LogCaptureFixture,
) -> None:
    # Flow's env runs SUMO from its construction and Flow's tests set a light right away;
    # here the command waits until reset starts the simulation
    env = grid_env(TrafficLightParams())
    try:
        k = env.k.traffic_light
        k.set_state("center0", "gggggggggggg")  # 12 characters, 4 links: as Flow's tests
        k.set_state("center1", "rGrG")
        with pytest.raises(KeyError, match="has not started"):
            k.get_state("center0")
        with pytest.raises(KeyError, match="no traffic light 'center9'"):
            k.set_state("center9", "GrGr")
        with caplog.at_level("WARNING", logger="flowrun.kernel.traffic_light"):
            env.reset(seed=0)
        api = env.k.vehicle.api.trafficlight
        assert api.getRedYellowGreenState("center0") == k.get_state("center0") == "gggg"
        assert api.getRedYellowGreenState("center1") == "rGrG"
        assert api.getRedYellowGreenState("center2") == "GrGr"  # the default program's
        warned = [r.getMessage() for r in caplog.records]
        assert len(warned) == 1 and "'center0' controls 4 links" in warned[0]
        assert "'gggggggg' are ignored" in warned[0]
        k.set_state("center0", "gggggggggggg")  # the same again: no second warning
        env.step(None)
        assert api.getRedYellowGreenState("center0") == "gggg"
        assert len(caplog.records) == 1
        env.reset(seed=0)  # sent once: the next start runs the programs again
        assert api.getRedYellowGreenState("center0") == "GrGr"
    finally:
        env.close()


@pytest.mark.sumo
def test_no_car_crosses_on_red_and_cars_are_conserved() -> None:
    tl = TrafficLightParams()
    for i in range(4):
        tl.add(f"center{i}", phases=PHASES)
    env = grid_env(tl, vph=900.0)
    try:
        env.reset(seed=0)
        k, vk = env.k.traffic_light, env.k.vehicle
        api = vk.api
        # 1 s steps: the inflows' first cars (begin 1 s) enter in reset's step, as in Flow
        departed, arrived = vk.num_vehicles, 0
        crossed = 0
        prev_edge: dict[str, str] = {}
        prev_state = {t: k.get_state(t) for t in k.get_ids()}
        links = {t: k.get_controlled_lanes(t) for t in k.get_ids()}
        for _ in range(200):
            env.step(None)
            departed += len(vk.get_departed_ids())
            arrived += len(vk.get_arrived_ids())
            assert departed == arrived + vk.num_vehicles
            for vid in vk.get_ids():
                lane = api.vehicle.getLaneID(vid)
                before = prev_edge.get(vid)
                if lane.startswith(":center") and before is not None and not before.startswith(":"):
                    node = lane[1:].rsplit("_", 2)[0]
                    # the state in force during the step (SUMO switches before moving cars)
                    signal = k.get_state(node)[links[node].index(before)]
                    assert signal != "r", (vid, node, before, prev_state[node])
                    crossed += 1
                prev_edge[vid] = lane
            prev_state = {t: k.get_state(t) for t in k.get_ids()}
        assert crossed > 50
        assert env.k.simulation.collisions == 0
    finally:
        env.close()


@pytest.mark.sumo
def test_commands_before_the_first_read_of_a_step_keep_the_snapshot_sumo_showed() -> None:
    """The snapshot is read when first asked in a step; commands issued before that still
    leave every other value as SUMO showed it right after the step."""
    tl = TrafficLightParams()
    for i in range(4):
        tl.add(f"center{i}", phases=PHASES, offset=i)
    env = grid_env(tl)
    try:
        env.reset(seed=0)
        k = env.k.traffic_light
        api = env.k.vehicle.api.trafficlight
        for _ in range(5):
            env.step(None)
        after_step = {t: (api.getRedYellowGreenState(t), api.getPhase(t), api.getProgram(t),
                          api.getNextSwitch(t)) for t in k.get_ids()}  # fmt: skip
        k.set_state("center0", "rGrG")
        k.set_state("center1", "y", link_index=2)
        with pytest.raises(ValueError, match="controls 4 links"):
            k.set_state("center2", "GrG")
        with pytest.raises(Exception, match="nosuch"):
            k.set_program("center3", "nosuch")
        state1 = after_step["center1"][0]
        expected = {
            "center0": ("rGrG", after_step["center0"][1], "online", after_step["center0"][3]),
            "center1": (state1[:2] + "y" + state1[3:], after_step["center1"][1], "online",
                        after_step["center1"][3]),
            "center2": after_step["center2"],
            "center3": after_step["center3"],
        }  # fmt: skip
        seen = {t: (k.get_state(t), k.get_phase(t), k.get_program(t), k.get_next_switch(t))
                for t in k.get_ids()}  # fmt: skip
        assert seen == expected
        assert api.getRedYellowGreenState("center0") == "rGrG"  # and SUMO has the commands
        assert api.getRedYellowGreenState("center1") == expected["center1"][0]
        env.step(None)  # the next step's snapshot is SUMO's again
        assert [k.get_state(t) for t in k.get_ids()] == [
            api.getRedYellowGreenState(t) for t in k.get_ids()
        ]
        assert k.time == env.k.simulation.time
    finally:
        env.close()
