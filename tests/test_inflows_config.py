"""``InFlows.add`` with Flow's arguments and semantics, and YAML ``network.inflows``."""

from __future__ import annotations

import textwrap
import warnings
from pathlib import Path

import pytest
import yaml

from flowrun.config import (
    ExperimentConfig,
    NetParams,
    NetworkConfig,
    VehicleParams,
    dump_config,
)
from flowrun.config.inflows import InFlow, InFlows
from flowrun.errors import ConfigError
from flowrun.loading import config_from_dict, load_config


def one(**kwargs: object) -> InFlow:
    flows = InFlows()
    flows.add(**{"edge": "bottom", "veh_type": "human", **kwargs})  # type: ignore[arg-type]
    return flows.get()[0]


# ------------------------------------------------------------------ Python API


def test_flow_defaults() -> None:
    flow = one(vehs_per_hour=1200)
    assert (flow.depart_lane, flow.depart_speed, flow.name) == ("first", 0, "flow")
    assert (flow.begin, flow.end, flow.number, flow.extra) == (1.0, 86400.0, None, {})


@pytest.mark.parametrize("rate", [{"vehs_per_hour": 1200}, {"probability": 0.2}, {"period": 3}])
def test_each_rate_alone_is_accepted(rate: dict[str, float]) -> None:
    flow = one(**rate)
    ((name, value),) = rate.items()
    assert getattr(flow, name) == value


def test_no_rate_is_an_error() -> None:
    with pytest.raises(ConfigError, match="exactly one of vehs_per_hour, probability or period"):
        one()


@pytest.mark.parametrize(
    "rates",
    [
        {"vehs_per_hour": 100, "probability": 0.1},
        {"vehs_per_hour": 100, "period": 2},
        {"probability": 0.1, "period": 2},
        {"vehs_per_hour": 100, "probability": 0.1, "period": 2},
    ],
)
def test_two_rates_are_an_error(rates: dict[str, float]) -> None:
    with pytest.raises(ConfigError, match="exactly one") as info:
        one(**rates)
    assert " and " in info.value.message


def test_begin_below_one_is_an_error() -> None:
    with pytest.raises(ConfigError, match="at least 1") as info:
        one(vehs_per_hour=100, begin=0)
    assert info.value.path == "begin"


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"vehs_per_hour": -5}, "vehs_per_hour"),
        ({"probability": 1.5}, "probability"),
        ({"period": 0}, "period"),
        ({"vehs_per_hour": 5, "number": 0}, "number"),
        ({"vehs_per_hour": 5, "begin": 100, "end": 50}, "end"),
    ],
)
def test_bad_values_name_their_argument(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(ConfigError) as info:
        one(**kwargs)
    assert info.value.path == field


def test_number_replaces_end_in_sumo_attributes() -> None:
    flow = one(vehs_per_hour=600, number=10, end=50)
    attrs = flow.sumo_attributes(3)
    assert attrs["number"] == "10" and "end" not in attrs
    assert attrs["id"] == "flow_3" and attrs["type"] == "human"
    assert "end" in one(vehs_per_hour=600).sumo_attributes(0)


def test_extra_keywords_are_kept_for_sumo() -> None:
    flow = one(period=2, color="1,0,0", departPos="free", arrivalPos=10)
    assert flow.extra == {"color": "1,0,0", "departPos": "free", "arrivalPos": 10}
    attrs = flow.sumo_attributes(0)
    assert attrs["color"] == "1,0,0" and attrs["departPos"] == "free"
    assert attrs["arrivalPos"] == "10" and attrs["period"] == "2"


def test_camel_case_names_still_work_with_a_warning() -> None:
    with pytest.warns(DeprecationWarning) as record:
        flow = one(vehsPerHour=900, departLane="free", departSpeed="max")
    messages = sorted(str(w.message) for w in record)
    assert messages == [
        f"InFlows.add: '{old}' is deprecated; use '{new}'"
        for old, new in sorted(
            [
                ("departLane", "depart_lane"),
                ("departSpeed", "depart_speed"),
                ("vehsPerHour", "vehs_per_hour"),
            ]
        )
    ]
    assert (flow.vehs_per_hour, flow.depart_lane, flow.depart_speed) == (900, "free", "max")
    assert flow.extra == {}


def test_snake_case_names_raise_no_warning() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        one(vehs_per_hour=900, depart_lane="best", depart_speed="random")


def test_flow_ids_follow_flow() -> None:
    flows = InFlows()
    flows.add(edge="bottom", veh_type="human", vehs_per_hour=100)
    flows.add(edge="top", veh_type="human", probability=0.1, name="ramp")
    assert flows.sumo_ids() == ["flow_0", "ramp_1"]
    assert flows.num_flows == 2


def test_sumo_field_names_in_extra_are_refused() -> None:
    with pytest.raises(ConfigError) as info:
        one(vehs_per_hour=1, type="r0")
    assert info.value.path == "extra"


# ------------------------------------------------------------------ YAML


def load_error(tmp_path: Path, text: str) -> tuple[ConfigError, Path]:
    path = tmp_path / "x.yaml"
    path.write_text(textwrap.dedent(text))
    with pytest.raises(ConfigError) as info:
        load_config(path)
    return info.value, path


def config_text(inflow: str) -> str:
    return textwrap.dedent(
        f"""\
        name: x
        network:
          type: ring
          inflows:
            - {inflow}
        vehicles: [{{id: human, count: 0}}, {{id: idm, count: 4}}]
        """
    )


@pytest.mark.parametrize(
    ("inflow", "path", "message"),
    [
        ("{edge: bottom, veh_type: human}", "vehs_per_hour", "exactly one"),
        ("{edge: bottom, veh_type: human, period: 1, probability: 0.5}", "period", "exactly"),
        ("{edge: bottom, veh_type: human, period: 1, begin: 0}", "begin", "at least 1"),
        ("{edge: bottom, veh_type: human, period: -1}", "period", "greater than 0"),
        ("{edge: botom, veh_type: human, period: 1}", "edge", "did you mean 'bottom'?"),
        ("{edge: bottom, veh_type: humn, period: 1}", "veh_type", "did you mean 'human'?"),
        ("{edge: bottom, veh_type: human, vehsPerHour: 1}", "vehsPerHour", "write 'vehs_per_hour'"),
        ("{edge: bottom, veh_type: human, period: 1, colr: red}", "colr", "under 'extra'"),
        ("{edge: bottom, veh_type: human, period: one}", "period", "expected"),
    ],
)
def test_yaml_inflow_errors_name_file_line_and_key(
    tmp_path: Path, inflow: str, path: str, message: str
) -> None:
    file = tmp_path / "x.yaml"
    file.write_text(config_text(inflow))
    with pytest.raises(ConfigError) as info:
        load_config(file)
    err = info.value
    assert err.location == f"{file}:5"
    assert err.path == f"network.inflows[0].{path}"
    assert message in err.message


def test_yaml_edge_error_lists_the_network_edges(tmp_path: Path) -> None:
    file = tmp_path / "x.yaml"
    file.write_text(config_text("{edge: inflow_highway, veh_type: human, period: 1}"))
    with pytest.raises(ConfigError, match="no edge 'inflow_highway' in the ring network") as info:
        load_config(file)
    assert "bottom, right, top, left" in info.value.message


def test_yaml_inflows_load_with_all_fields_and_round_trip(tmp_path: Path) -> None:
    file = tmp_path / "x.yaml"
    file.write_text(
        config_text(
            "{edge: top, veh_type: human, vehs_per_hour: 1800, depart_lane: free,"
            " depart_speed: max, name: main, begin: 5, number: 30,"
            " extra: {color: blue, departPos: last}}"
        )
    )
    cfg = load_config(file)
    inflows = cfg.network.net_params.inflows
    assert inflows is not None
    (flow,) = inflows.get()
    assert flow == InFlow(
        edge="top",
        veh_type="human",
        vehs_per_hour=1800.0,
        depart_lane="free",
        depart_speed="max",
        name="main",
        begin=5.0,
        number=30,
        extra={"color": "blue", "departPos": "last"},
    )
    assert cfg.vehicles.get_type("human").num_vehicles == 0  # inflow-only type
    again = config_from_dict(yaml.safe_load(dump_config(cfg)))
    assert again == cfg


def test_python_inflows_dump_and_load_equal() -> None:
    flows = InFlows()
    flows.add(edge="left", veh_type="human", probability=0.25, depart_lane=0, color="red")
    vehicles = VehicleParams()
    vehicles.add("human", num_vehicles=0)
    cfg = ExperimentConfig(
        name="x", network=NetworkConfig("ring", NetParams(inflows=flows)), vehicles=vehicles
    )
    assert config_from_dict(yaml.safe_load(dump_config(cfg))) == cfg


def test_a_network_that_cannot_be_built_is_reported_at_its_key(tmp_path: Path) -> None:
    err, file = load_error(
        tmp_path,
        """\
        name: x
        network:
          type: template
          template: nowhere.net.xml
        vehicles: []
        """,
    )
    assert (err.location, err.path) == (f"{file}:4", "network.template")
    assert "nowhere.net.xml" in err.message
