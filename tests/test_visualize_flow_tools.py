"""Flow's visualisation tools at Flow's paths: the bottleneck capacity diagram's data
(``capacity_diagram_generator``) and training curves from a ``progress.csv``
(``plot_ray_results``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flowrun.errors import ConfigError
from flowrun.visualize.capacity_diagram_generator import (
    create_parser,
    get_capacity_data,
    import_data_from_csv,
)
from flowrun.visualize.plot_ray_results import create_parser as progress_parser
from flowrun.visualize.plot_ray_results import plot_progress


def test_capacity_data_groups_outflows_by_inflow(tmp_path: Path) -> None:
    path = tmp_path / "sweep.csv"
    path.write_text("1000, 978\n1500, 1134\n1000, 773\n1500, 1200\n2000, 1300\n")
    data = import_data_from_csv(path)
    assert data == {"inflows": [1000.0, 1500.0, 1000.0, 1500.0, 2000.0],
                    "outflows": [978.0, 1134.0, 773.0, 1200.0, 1300.0]}  # fmt: skip
    inflows, mean, std = get_capacity_data(data)
    assert inflows == [1000.0, 1500.0, 2000.0]
    np.testing.assert_allclose(mean, [875.5, 1167.0, 1300.0])
    np.testing.assert_allclose(std, [102.5, 33.0, 0.0])
    assert create_parser().parse_args([str(path)]).file == str(path)


def test_a_bad_capacity_row_names_its_line(tmp_path: Path) -> None:
    path = tmp_path / "sweep.csv"
    path.write_text("1000, 978\n1500\n")
    with pytest.raises(ConfigError, match="expected 'inflow, outflow'") as info:
        import_data_from_csv(path)
    assert info.value.location == f"{path}:2"


def test_progress_columns_are_plotted_and_unknown_ones_listed(tmp_path: Path) -> None:
    path = tmp_path / "progress.csv"
    path.write_text("episode_reward_mean,episode_reward_max\n1.5,2\n2.5,4\n3.0,5\n")
    fig = plot_progress(path, ["episode_reward_mean", "episode_reward_max"])
    (ax,) = fig.axes
    assert [line.get_label() for line in ax.lines] == ["episode_reward_mean",
                                                       "episode_reward_max"]  # fmt: skip
    assert list(ax.lines[1].get_ydata()) == [2.0, 4.0, 5.0]
    with pytest.raises(ConfigError, match="no column 'reward'; the file has: episode_reward_mean"):
        plot_progress(path, ["reward"])
    with pytest.raises(KeyError):  # what Flow raises for an unknown column
        plot_progress(path, ["reward"])
    path.write_text("episode_reward_mean,info\n1.5,{}\n")
    with pytest.raises(ValueError, match=r"column 'info' holds '\{\}', not a number"):  # as Flow
        plot_progress(path, ["info"])
    with pytest.raises(ConfigError, match="name the columns to plot"):
        plot_progress(path, [])
    args = progress_parser().parse_args([str(path), "a", "b"])
    assert args.columns == ["a", "b"]


def test_rllib_trial_files_are_read_from_the_checkpoint_or_its_parent(tmp_path: Path) -> None:
    import json
    import pickle

    from flowrun.utils.rllib import get_rllib_config, get_rllib_pkl

    (tmp_path / "params.json").write_text(json.dumps({"env": "MergePOEnv-v0", "gamma": 0.99}))
    (tmp_path / "params.pkl").write_bytes(pickle.dumps({"env_config": {"flow_params": "{}"}}))
    checkpoint = tmp_path / "checkpoint_000010"
    checkpoint.mkdir()
    assert get_rllib_config(checkpoint) == {"env": "MergePOEnv-v0", "gamma": 0.99}
    assert get_rllib_pkl(tmp_path)["env_config"] == {"flow_params": "{}"}
    with pytest.raises(ValueError, match=r"no params\.json in"):
        get_rllib_config(checkpoint / "nested")


def test_flows_xml_helpers_write_a_sumo_schema_file(tmp_path: Path) -> None:
    import xml.etree.ElementTree as ET

    from flowrun.core.util import makexml, printxml

    routes = makexml("routes", "http://sumo.dlr.de/xsd/routes_file.xsd")
    routes.append(ET.Element("route", {"id": "r0", "edges": "a b"}))
    path = tmp_path / "x.rou.xml"
    printxml(routes, path)
    text = path.read_text()
    assert text.startswith("<?xml version='1.0' encoding='UTF-8'?>")
    assert 'xsi:noNamespaceSchemaLocation="http://sumo.dlr.de/xsd/routes_file.xsd"' in text
    root = ET.parse(path).getroot()
    assert root.tag == "routes" and root.find("route").get("edges") == "a b"
