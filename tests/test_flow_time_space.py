"""Flow's trajectory time-space diagram: ``import_data_from_trajectory`` → ``get_time_space_data``
→ ``plot_tsd``, with Flow's signatures, on a hand-written CSV and on a real run's CSV."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from flowrun.core.params import NetParams
from flowrun.errors import RecordingError
from flowrun.networks.ring import RingNetwork
from flowrun.visualize.time_space_diagram import (
    get_time_space_data,
    import_data_from_trajectory,
    plot_tsd,
)

pytest.importorskip("pandas")

#: two cars, three steps each; car b's rows come first (as Flow's files group by vehicle)
CSV = """time,id,speed,edge_id,lane_number,relative_position
0.0,b,2.0,right,0,1.0
0.1,b,3.0,right,0,1.5
0.2,b,4.0,top,0,0.5
0.0,a,5.0,bottom,0,10.0
0.1,a,6.0,bottom,0,10.6
0.2,a,7.0,bottom,0,11.3
"""


def ring_params() -> dict[str, object]:
    net = NetParams(additional_params={"length": 230, "lanes": 1, "speed_limit": 30,
                                       "resolution": 40})  # fmt: skip
    return {"network": RingNetwork, "net": net}


def test_trajectory_without_distance_gets_it_from_the_ring_edge_starts(tmp_path: Path) -> None:
    path = tmp_path / "ring-0_emission.csv"
    path.write_text(CSV)
    df = import_data_from_trajectory(path, ring_params())
    # last sample of each car dropped; columns renamed as Flow does
    assert list(df["id"]) == ["b", "b", "a", "a"]
    assert {"time_step", "lane_id", "next_pos", "next_time"} <= set(df.columns)
    # edge starts of a 230 m ring: bottom 0, right 57.5, top 115
    assert list(df["distance"]) == pytest.approx([58.5, 59.0, 10.0, 10.6])
    assert list(df["next_pos"]) == pytest.approx([59.0, 115.5, 10.6, 11.3])
    assert list(df["next_time"]) == pytest.approx([0.1, 0.2, 0.1, 0.2])
    segs, same = get_time_space_data(df, ring_params())
    assert same is df and segs.shape == (4, 2, 2)
    assert segs[1].ravel().tolist() == pytest.approx([0.1, 59.0, 0.2, 115.5])


def test_plot_tsd_colours_each_segment_by_speed_with_flows_labels(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    path.write_text(CSV)
    df = import_data_from_trajectory(path, ring_params())
    segs, df = get_time_space_data(df, ring_params())
    fig = Figure()
    ax = fig.add_subplot()
    args = argparse.Namespace(min_speed=0, max_speed=8, start=0.05)
    lines = plot_tsd(ax, df, segs, args, lane=2)
    assert np.asarray(lines.get_array()).tolist() == [2.0, 3.0, 5.0, 6.0]
    assert lines.norm.vmin == 0 and lines.norm.vmax == 8
    assert ax.get_title() == "Time-Space Diagram: Lane 2"
    assert ax.get_xlabel() == "Time (s)" and ax.get_ylabel() == "Position (m)"
    # x range: time 0..0.1 with 2.5 % margins
    assert ax.get_xlim() == pytest.approx((-0.0025, 0.1025))
    out = tmp_path / "tsd.png"
    FigureCanvasAgg(fig).print_png(str(out))
    assert out.stat().st_size > 0


def test_a_file_without_distance_needs_the_network(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    path.write_text(CSV)
    with pytest.raises(RecordingError, match="no 'distance' column"):
        import_data_from_trajectory(path)
    with pytest.raises(RecordingError, match="no such trajectory file"):
        import_data_from_trajectory(tmp_path / "missing.csv")


def test_a_real_runs_csv_plots_every_car(tmp_path: Path) -> None:
    from flowrun.core.experiment import Experiment
    from flowrun.core.params import SumoParams
    from tests.test_flow_params import ring_params as flow_ring_params

    params = flow_ring_params(sim=SumoParams(sim_step=0.1, emission_path=str(tmp_path)))
    exp = Experiment(params)
    exp.run(1, 10, convert_to_csv=True)
    df = import_data_from_trajectory(exp.csv_files[0], params)
    assert df["id"].nunique() == 22
    # the run's odometer column is used as is; every segment moves forward in time
    segs, df = get_time_space_data(df, params)
    assert segs.shape == (len(df), 2, 2)
    assert bool(np.all(segs[:, 1, 0] > segs[:, 0, 0]))
    assert bool(np.all(segs[:, 1, 1] >= segs[:, 0, 1]))
    fig = Figure()
    lines = plot_tsd(fig.add_subplot(), df, segs, {"min_speed": 0, "max_speed": 10})
    assert len(lines.get_segments()) == len(df)
