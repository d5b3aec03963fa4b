"""The ``traffic_lights:`` YAML section: loading, errors at file:line, round trip, flow_params."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from flowrun.config.dump import config_to_dict, dump_config
from flowrun.config.params import TrafficLightParams
from flowrun.envs.factory import make_network
from flowrun.errors import ConfigError
from flowrun.loading.flow_params import from_flow_params
from flowrun.loading.loader import config_from_dict, load_config

ROOT = Path(__file__).resolve().parents[1]
GRID0 = (ROOT / "configs" / "grid0.yaml").read_text()

LIGHTS = """\
traffic_lights:
  baseline: false
  lights:
    - node_id: center0
      tls_type: static
      programID: 10
      offset: 5
      phases:
        - {duration: 31, state: GrGr}
        - {duration: 3, state: yryr}
        - {duration: 31, state: rGrG}
        - {duration: 3, state: ryry}
    - node_id: center4
      tls_type: actuated
      maxGap: 2.5
      phases:
        - {duration: 31, state: GrGr, minDur: 8, maxDur: 45}
        - {duration: 6, state: yryr}
        - {duration: 31, state: rGrG, minDur: 8, maxDur: 45}
        - {duration: 6, state: ryry}
"""


def write(tmp_path: Path, section: str) -> Path:
    path = tmp_path / "grid.yaml"
    path.write_text(GRID0 + textwrap.dedent(section))
    return path


def line_of(path: Path, text: str) -> int:
    lines = path.read_text().splitlines()
    return max(i + 1 for i, line in enumerate(lines) if text in line)  # the last one


def error(path: Path) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        load_config(path)
    return info.value


def test_yaml_lights_are_flows_traffic_light_params(tmp_path: Path) -> None:
    cfg = load_config(write(tmp_path, LIGHTS))
    expected = TrafficLightParams()
    expected.add("center0", "static", 10, 5, [
        {"duration": 31, "state": "GrGr"}, {"duration": 3, "state": "yryr"},
        {"duration": 31, "state": "rGrG"}, {"duration": 3, "state": "ryry"}])  # fmt: skip
    expected.add("center4", "actuated", phases=[
        {"duration": 31, "state": "GrGr", "minDur": 8, "maxDur": 45},
        {"duration": 6, "state": "yryr"},
        {"duration": 31, "state": "rGrG", "minDur": 8, "maxDur": 45},
        {"duration": 6, "state": "ryry"}], maxGap=2.5)  # fmt: skip
    assert cfg.traffic_lights.programs == expected
    assert cfg.traffic_lights.controller is None
    assert make_network(cfg).traffic_lights == expected


def test_resolved_config_round_trips(tmp_path: Path) -> None:
    cfg = load_config(write(tmp_path, LIGHTS))
    assert config_from_dict(config_to_dict(cfg)) == cfg
    again = tmp_path / "again.yaml"
    again.write_text(dump_config(cfg))
    assert load_config(again) == cfg
    light = config_to_dict(cfg)["traffic_lights"]["lights"][1]
    assert (light["maxGap"], light["detectorGap"], light["showDetectors"]) == (2.5, 0.6, True)


def test_configs_without_lights_dump_no_section() -> None:
    cfg = load_config(ROOT / "configs" / "grid0.yaml")
    assert cfg.traffic_lights.is_default
    assert "traffic_lights" not in config_to_dict(cfg)


def test_state_length_error_names_node_expected_length_and_line(tmp_path: Path) -> None:
    path = write(tmp_path, LIGHTS.replace("state: rGrG}", "state: rGr}", 1))
    err = error(path)
    assert err.location == f"{path}:{line_of(path, 'rGr}')}"
    assert err.path == "traffic_lights.lights[0].phases[2].state"
    assert "'center0'" in err.message and "controls 4 links" in err.message
    assert "3 characters" in err.message


@pytest.mark.parametrize(
    ("old", "new", "key", "words"),
    [
        ("state: yryr}", "state: yrxr}", "lights[0].phases[1].state", "unknown signal character"),
        ("programID: 10", "programId: 10", "lights[0].programId", "did you mean 'programID'"),
        ("maxGap: 2.5", "maxgap: 2.5", "lights[1].maxgap", "did you mean 'maxGap'"),
        ("offset: 5", "maxGap: 5", "lights[0].maxGap", "actuated lights only"),
        ("tls_type: static", "tls_type: statc", "lights[0].tls_type", "did you mean 'static'"),
        ("node_id: center0", "node_id: centre0", "lights[0].node_id", "did you mean 'center0'"),
        ("node_id: center4", "node_id: center0", "lights[1].node_id", "declared twice"),
        ("baseline: false", "baselin: false", "baselin", "did you mean 'baseline'"),
        ("baseline: false", "baseline: 3", "baseline", "true or false"),
        ("offset: 5", "offset: -5", "lights[0].offset", ">= 0"),
        ("minDur: 8, maxDur: 45}", "minDur: 50, maxDur: 45}", "lights[1].phases[0].minDur",
         "minDur 50.0 > maxDur 45.0"),
    ],
)
def test_bad_lights_are_reported_at_their_key(
    tmp_path: Path, old: str, new: str, key: str, words: str
) -> None:
    path = write(tmp_path, LIGHTS.replace(old, new, 1))
    err = error(path)
    assert err.path == f"traffic_lights.{key}"
    assert words in err.message
    assert err.location == f"{path}:{line_of(path, new)}"


def test_controller_is_chosen_in_yaml_and_by_override() -> None:
    cfg = load_config(ROOT / "configs" / "grid0.yaml", ["traffic_lights.controller=actuated"])
    assert cfg.traffic_lights.controller == "actuated"
    assert make_network(cfg).traffic_lights == TrafficLightParams(baseline=True)
    fixed = load_config(ROOT / "configs" / "grid0.yaml", ["traffic_lights.controller=fixed_time",
                                                           "traffic_lights.yellow=4"])  # fmt: skip
    props = make_network(fixed).traffic_lights.get_properties()
    assert sorted(props) == [f"center{i}" for i in range(9)]
    assert [p["duration"] for p in props["center0"]["phases"]] == [31.0, 4.0, 31.0, 4.0]


@pytest.mark.parametrize(
    ("config", "sets", "words"),
    [
        ("grid0", ["traffic_lights.controller=max_presure"], "did you mean 'max_pressure'"),
        ("sugiyama", ["traffic_lights.controller=actuated"], "ring network has none"),
        ("grid0", ["traffic_lights.controller=actuated", "traffic_lights.baseline=true"],
         "remove 'baseline'"),
    ],
)
def test_bad_controllers_are_errors(config: str, sets: list[str], words: str) -> None:
    with pytest.raises(ConfigError, match=words) as info:
        load_config(ROOT / "configs" / f"{config}.yaml", sets)
    assert info.value.path == "traffic_lights.controller"


def test_flow_params_tls_becomes_the_section() -> None:
    from flowrun.loading.flow_params import FLOW_KEYS  # noqa: F401  (module importable)

    cfg = load_config(ROOT / "configs" / "grid0.yaml")
    tls = TrafficLightParams()
    tls.add("center1", phases=[{"duration": "20", "state": "GrGr"},
                               {"duration": "20", "state": "rGrG"}])  # fmt: skip
    params = {
        "exp_tag": "grid", "env_name": "TrafficLightGridBenchmarkEnv",
        "network": "TrafficLightGridNetwork", "simulator": "traci", "sim": cfg.sim,
        "env": cfg.env, "net": cfg.network.net_params, "veh": cfg.vehicles,
        "initial": cfg.initial, "tls": tls,
    }  # fmt: skip
    flow = from_flow_params(params)
    assert flow.config.traffic_lights.programs == tls
    assert flow.traffic_lights == tls
    data = config_to_dict(flow.config)
    assert data["traffic_lights"]["lights"][0]["node_id"] == "center1"
    bad = TrafficLightParams()
    bad.add("center1", phases=[{"duration": 20, "state": "GrG"}])
    with pytest.raises(ConfigError, match="controls 4 links"):
        from_flow_params({**params, "tls": bad})


@pytest.mark.sumo
def test_flows_grid_states_longer_than_the_links_load_and_run(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Flow's grid example gives 12-character states to 4-link junctions; SUMO ignores the
    extra characters, and so does flowrun, with one warning at load."""
    from flowrun.envs.factory import make_env

    long_lights = LIGHTS.replace("state: GrGr}", "state: GrGrGrGrGrGr}", 1)
    with caplog.at_level("WARNING", logger="flowrun.networks.tls"):
        cfg = load_config(write(tmp_path, long_lights))
    (record,) = [r for r in caplog.records if r.name == "flowrun.networks.tls"]
    message = record.getMessage()
    assert "'center0' controls 4 links" in message and "('GrGrGrGr')" in message
    env = make_env(cfg)
    try:
        env.reset(seed=0)
        env.step(None)
        assert env.k.traffic_light.get_state("center0") in {"GrGr", "yryr", "rGrG", "ryry"}
    finally:
        env.close()
