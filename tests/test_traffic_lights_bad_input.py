"""Bad signal input (issue 11): each is one clear message naming the place, and exit code 1.

A light on a node that is not a junction, phases with unknown characters, an actuated program
without room for its detectors, a state whose length is not the junction's number of links,
an RL signal env on a network without lights (or not a grid). The CLI cases run netconvert on
Flow's grid0 (no simulation steps).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.params import NetParams, TrafficLightParams, VehicleParams
from flowrun.errors import ConfigError
from flowrun.networks.tls import check_programs
from flowrun.networks.tls_detectors import detector_distance
from flowrun.networks.traffic_light_grid import TrafficLightGridNetwork

ROOT = Path(__file__).resolve().parents[1]
GRID0 = (ROOT / "configs" / "grid0.yaml").read_text()
SUGIYAMA = (ROOT / "configs" / "sugiyama.yaml").read_text()
SUGIYAMA_PARAMS = "{max_accel: 1, max_decel: 1, target_velocity: 10, sort_vehicles: false}"
LIGHT = """\
traffic_lights:
  lights:
    - node_id: {node}
      tls_type: actuated
      phases:
        - {{duration: 31, state: {state}, minDur: 8, maxDur: 45}}
        - {{duration: 6, state: yryr}}
        - {{duration: 31, state: rGrG, minDur: 8, maxDur: 45}}
        - {{duration: 6, state: ryry}}
"""
ACTUATED = [
    {"duration": 31, "state": "GrGr", "minDur": 8, "maxDur": 45},
    {"duration": 6, "state": "yryr"},
    {"duration": 31, "state": "rGrG", "minDur": 8, "maxDur": 45},
    {"duration": 6, "state": "ryry"},
]


def test_detector_distance_is_sumos_rule() -> None:
    # detector-gap x speed, unless the shortest minDur cannot clear the cars before it
    assert detector_distance(0.6, 35.0, 8.0) == pytest.approx(21.0)
    assert detector_distance(3.0, 35.0, 5.0) == pytest.approx((5.0 / 1.9 + 0.5) * 7.5)


def one_by_one(length: float, tl: TrafficLightParams) -> TrafficLightGridNetwork:
    grid = {"row_num": 1, "col_num": 1, "inner_length": length, "short_length": length,
            "long_length": length}  # fmt: skip
    params = NetParams(additional_params={"grid_array": grid, "speed_limit": 35})
    return TrafficLightGridNetwork("g", VehicleParams(), params, traffic_lights=tl)


@pytest.mark.sumo
def test_actuated_light_needs_room_for_its_detectors_static_does_not() -> None:
    tl = TrafficLightParams()
    tl.add("center0", tls_type="actuated", phases=ACTUATED)
    with pytest.raises(ConfigError, match=r"no room for its detector on lane '\w+_0'") as err:
        check_programs(one_by_one(15.0, tl), tl)
    assert err.value.path == "traffic_lights.center0.tls_type"
    assert "15 m long" in err.value.message and "21 m before the stop line" in err.value.message
    check_programs(one_by_one(30.0, tl), tl)  # 30 m leave room for 21 m
    short_gap = TrafficLightParams()
    short_gap.add("center0", tls_type="actuated", phases=ACTUATED, detectorGap=0.2)  # 7 m
    check_programs(one_by_one(15.0, short_gap), short_gap)
    static = TrafficLightParams()
    static.add("center0", phases=[{"duration": 31, "state": "GrGr"},
                                  {"duration": 31, "state": "rGrG"}])  # fmt: skip
    check_programs(one_by_one(15.0, static), static)


def bad_config(tmp_path: Path, case: str) -> Path:
    text = {
        "not_a_junction": GRID0 + LIGHT.format(node="bot_col_short0", state="GrGr"),
        "unknown_character": GRID0 + LIGHT.format(node="center4", state="GrXr"),
        "no_detector_room": GRID0.replace("inner_length: 300", "inner_length: 15")
        + LIGHT.format(node="center4", state="GrGr"),
        "rl_without_lights": GRID0.replace(
            "  speed_limit: 35\n", "  speed_limit: 35\n  traffic_lights: false\n"
        ),
        "state_length": GRID0 + LIGHT.format(node="center4", state="GrG"),
        "signal_env_on_a_ring": SUGIYAMA.replace("class: AccelEnv", "class: TrafficLightGridPOEnv")
        .replace(SUGIYAMA_PARAMS, "{target_velocity: 50, switch_time: 3, num_observed: 2, "
                 "discrete: false, tl_type: actuated}"),
    }[case]
    path = tmp_path / f"{case}.yaml"
    path.write_text(text)
    return path


def line_of(path: Path, text: str) -> int:
    return next(i + 1 for i, line in enumerate(path.read_text().splitlines()) if text in line)


@pytest.mark.sumo
@pytest.mark.parametrize(
    ("case", "command", "at", "words"),
    [
        ("not_a_junction", "validate", "node_id: bot_col_short0",
         "no traffic-light junction 'bot_col_short0'"),
        ("unknown_character", "validate", "state: GrXr", "unknown signal character(s) 'X'"),
        ("no_detector_room", "validate", "tls_type: actuated",
         "actuated light 'center4' has no room for its detector"),
        ("rl_without_lights", "baseline", "traffic_lights: false",
         "TrafficLightGridBenchmarkEnv switches traffic lights, but network "
         "'traffic_light_grid' has none (traffic_lights: false); set network.traffic_lights: "
         "true"),
        ("rl_without_lights", "validate", "traffic_lights: false",
         "network.traffic_lights: TrafficLightGridBenchmarkEnv switches traffic lights"),
        ("state_length", "baseline", "state: GrG",
         "state 'GrG' has 3 characters but junction 'center4' controls 4 links"),
        ("signal_env_on_a_ring", "baseline", "type: ring",
         "TrafficLightGridPOEnv switches traffic lights, but network 'ring' has none; use "
         "network type traffic_light_grid, or put lights on its junctions"),
    ],
)  # fmt: skip
def test_bad_signal_input_is_one_line_and_exit_1(
    tmp_path: Path, case: str, command: str, at: str, words: str
) -> None:
    path = bad_config(tmp_path, case)
    args = [command, str(path)]
    if command == "baseline":
        args += ["--steps", "2", "--out", str(tmp_path / "runs")]
    out = CliRunner().invoke(app, args)
    assert out.exit_code == 1, out.output
    lines = out.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), out.output
    assert words in lines[0]
    assert "Traceback" not in out.output
    # every one names the file and the line to change
    assert f"{path}:{line_of(path, at)}:" in lines[0]
