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


FIG8_CSV = """time,id,speed,edge_id,lane_number,relative_position
1.0,a,1.0,top,0,20.0
2.0,a,1.0,top,0,28.0
1.0,b,1.0,upper_ring,0,20.0
2.0,b,1.0,upper_ring,0,21.0
1.0,c,1.0,left,0,25.0
2.0,c,1.0,left,0,26.0
"""


def test_figure_eight_diagram_is_folded_at_the_intersection_as_flows(tmp_path: Path) -> None:
    from flowrun.networks.figure_eight import FigureEightNetwork

    path = tmp_path / "fig8.csv"
    path.write_text(FIG8_CSV)
    net = NetParams(additional_params={"radius_ring": 30, "lanes": 1, "speed_limit": 30,
                                       "resolution": 40})  # fmt: skip
    segs, _ = get_time_space_data(
        import_data_from_trajectory(path, {"network": FigureEightNetwork, "net": net}),
        {"network": FigureEightNetwork, "net": net},
    )
    # Flow's layout: intersection middles c0 = 30.28 + 30, c1 = 238.41 + 30 (edge starts of
    # :center_1 / :center_0 + the radius); its length L = 6 * 15 pi + 120 + 12.4 + 2.8
    c0, c1 = 60.28, 238.41166941154066 + 30
    length = 90 * np.pi + 135.2
    top, upper, left = 36.48, 66.76, 244.61166941154067
    # a: before c0 then past it; b: between c0 and c1; c: past c1
    np.testing.assert_allclose(segs[:, :, 1], [
        [c0 - (top + 20), (top + 28) - c1],
        [upper + 20 - c1, upper + 21 - c1],
        [c0 + length - (left + 25), c0 + length - (left + 26)],
    ])  # fmt: skip
    # cars running to the intersection from either side meet at 0 there
    assert abs(segs[0, 0, 1]) < abs(segs[0, 0, 1] - segs[2, 0, 1])


def test_merge_diagram_keeps_flows_on_ramp_edges(tmp_path: Path) -> None:
    from flowrun.networks.merge import MergeNetwork

    path = tmp_path / "merge.csv"
    path.write_text("""time,id,speed,edge_id,lane_number,relative_position
0.2,h,0.0,inflow_highway,0,4.86
0.4,h,0.1,inflow_highway,0,4.88
0.2,m,0.0,inflow_merge,0,6.89
0.4,m,0.2,inflow_merge,0,6.93
""")
    net = NetParams(additional_params={"merge_length": 100, "pre_merge_length": 500,
                                       "post_merge_length": 100, "merge_lanes": 1,
                                       "highway_lanes": 1, "speed_limit": 30})  # fmt: skip
    params = {"network": MergeNetwork, "net": net}
    segs, data = get_time_space_data(import_data_from_trajectory(path, params), params)
    assert list(data["id"]) == ["m"]
    np.testing.assert_allclose(segs, [[[0.2, 722.6 + 6.89], [0.4, 722.6 + 6.93]]])
