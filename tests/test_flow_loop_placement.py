"""Flow's uniform placement on a loop with junction links (the figure eight): cursors along
Flow's line, a car that would start on a junction link starts at the next edge instead."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowrun.config.params import InitialConfig, NetParams, VehicleParams
from flowrun.networks import FigureEightNetwork, MergeNetwork
from flowrun.networks.flow_line import flow_loop_line


def eight(n: int, lanes: int = 1, **initial: object) -> FigureEightNetwork:
    vehicles = VehicleParams()
    vehicles.add("test", num_vehicles=n)
    net = NetParams(additional_params={"radius_ring": 30, "lanes": lanes})
    return FigureEightNetwork("f8", vehicles, net, InitialConfig(**initial))  # type: ignore[arg-type]


def xs(net: FigureEightNetwork, seed: int = 0) -> tuple[list[str], np.ndarray]:
    start = net.start_positions(np.random.default_rng(seed))
    starts = net.spec.edge_starts
    return start.edges, np.array([starts[e] + p for e, p in zip(start.edges, start.lane_pos,
                                                                   strict=True)])  # fmt: skip


def test_cars_step_evenly_along_flows_line_from_x0() -> None:
    net = eight(15, x0=150)
    line = flow_loop_line(net.spec)
    assert line is not None and any(e.startswith(":") for _, e in line)
    ends = [x + e.length for e in net.spec.edges for x, name in line if name == e.id]
    total = max(ends) + net.spec.edge_starts["bottom"]  # + the link before the first edge
    step = total / 15
    edges, x = xs(net)
    assert x[0] == pytest.approx(150.0)
    assert not any(e.startswith(":") for e in edges)
    gaps = np.mod(np.diff(x), total)
    snapped = [i + 1 for i, g in enumerate(gaps) if not math.isclose(g, step)]
    # every uneven gap ends at a car moved off a junction link to the start of the next edge
    assert snapped, "x0=150 puts a car on a link"
    starts = net.spec.edge_starts
    for i in snapped:
        assert x[i] == pytest.approx(starts[edges[i]])
        assert gaps[i - 1] > step


def test_lanes_take_turns_and_each_lane_keeps_its_own_cursor() -> None:
    _, x = xs(eight(8, lanes=2))
    start = eight(8, lanes=2).start_positions(np.random.default_rng(0))
    assert start.lanes == [0, 1] * 4
    assert list(x[0::2]) == list(x[1::2])  # side by side, as Flow places them


def test_a_merge_is_not_a_loop_and_keeps_flowruns_edge_placement() -> None:
    vehicles = VehicleParams()
    vehicles.add("h", num_vehicles=4)
    merge = MergeNetwork("m", vehicles, NetParams(), InitialConfig())
    assert flow_loop_line(merge.spec) is None


def test_too_many_cars_for_the_loop_are_refused() -> None:
    from flowrun.errors import ConfigError

    with pytest.raises(ConfigError, match="vehicles need"):
        eight(80).start_positions(np.random.default_rng(0))
