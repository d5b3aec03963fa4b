"""Ring networks: initial placement (pure), the generated XML and netconvert's output."""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from flowrun.config.params import InitialConfig
from flowrun.errors import SimulationError
from flowrun.networks.build import build_network, edges_xml
from flowrun.networks.placement import place_on_closed_road
from flowrun.networks.ring import ring_edge_count, ring_spec


def place(
    n: int = 22,
    length: float = 230.0,
    lanes: int = 1,
    seed: int = 0,
    lengths: list[float] | None = None,
    **initial: object,
) -> tuple[np.ndarray, np.ndarray]:
    pos, lane = place_on_closed_road(
        length,
        lanes,
        lengths if lengths is not None else [5.0] * n,
        InitialConfig(**initial),  # type: ignore[arg-type]
        np.random.default_rng(seed),
    )
    return np.array(pos), np.array(lane)


def ring_gaps(pos: np.ndarray, length: float) -> np.ndarray:
    """Front-to-front distances between consecutive cars around the ring, m."""
    s = np.sort(pos)
    return np.diff(np.append(s, s[0] + length))


# --- placement -----------------------------------------------------------------------------


def test_uniform_spacing_fills_the_ring_evenly() -> None:
    pos, lanes = place(22, 230.0)
    np.testing.assert_allclose(pos, np.arange(22) * 230.0 / 22, rtol=0, atol=1e-12)
    assert set(lanes.tolist()) == {0}


def test_bunching_squeezes_cars_into_length_minus_bunching() -> None:
    pos, _ = place(22, 230.0, bunching=20.0)
    np.testing.assert_allclose(np.diff(pos), 210.0 / 22, rtol=0, atol=1e-12)
    assert pos[0] == 0.0
    assert ring_gaps(pos, 230.0)[-1] == pytest.approx(210.0 / 22 + 20.0)


def test_x0_shifts_all_cars_and_wraps() -> None:
    pos, _ = place(4, 100.0, x0=90.0)
    np.testing.assert_allclose(pos, [90.0, 15.0, 40.0, 65.0], atol=1e-12)


def test_perturbation_is_seeded_gaussian_noise_on_the_uniform_slots() -> None:
    base, _ = place(22, 230.0, bunching=20.0)
    a, _ = place(22, 230.0, seed=5, bunching=20.0, perturbation=1.0)
    b, _ = place(22, 230.0, seed=5, bunching=20.0, perturbation=1.0)
    c, _ = place(22, 230.0, seed=6, bunching=20.0, perturbation=1.0)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    offsets = (a - base + 115.0) % 230.0 - 115.0
    assert 0.0 < np.abs(offsets).max() < 5.0
    assert 0.4 < offsets.std() < 1.6


def test_random_spacing_keeps_minimum_gaps_and_is_seeded() -> None:
    lengths = [5.0] * 10 + [8.0] * 10
    for seed in range(20):
        pos, _ = place(
            20, 230.0, seed=seed, lengths=lengths, spacing="random", min_gap=2.5, bunching=10.0
        )
        # every car occupies at least the longest vehicle + min_gap, wrap-around included
        assert ring_gaps(pos, 230.0).min() >= 8.0 + 2.5 - 1e-9
    a, _ = place(20, 230.0, seed=1, lengths=lengths, spacing="random", min_gap=2.5)
    b, _ = place(20, 230.0, seed=1, lengths=lengths, spacing="random", min_gap=2.5)
    c, _ = place(20, 230.0, seed=2, lengths=lengths, spacing="random", min_gap=2.5)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_shuffle_permutes_which_car_takes_which_slot() -> None:
    plain, _ = place(22, 230.0, bunching=20.0)
    a, _ = place(22, 230.0, seed=3, bunching=20.0, shuffle=True)
    b, _ = place(22, 230.0, seed=3, bunching=20.0, shuffle=True)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, plain)
    np.testing.assert_allclose(np.sort(a), plain, atol=1e-12)  # same slots, other owners


def test_two_lanes_alternate_and_space_cars_per_lane() -> None:
    pos, lanes = place(44, 230.0, lanes=2, bunching=20.0)
    assert lanes.tolist() == [0, 1] * 22
    for lane in (0, 1):
        np.testing.assert_allclose(np.diff(pos[lanes == lane]), 210.0 / 22, atol=1e-12)
    one, lanes_one = place(44, 460.0, lanes=2, lanes_distribution=1)
    assert set(lanes_one.tolist()) == {0}
    np.testing.assert_allclose(np.diff(one), 460.0 / 44, atol=1e-12)


# --- network XML and netconvert ------------------------------------------------------------


@pytest.mark.parametrize("length", [230.0, 260.0, 2300.0, 23000.0])
def test_ring_edges_add_up_to_the_ring_length(length: float) -> None:
    spec = ring_spec(length, 1, 30.0, 40)
    assert sum(e.length for e in spec.edges) == pytest.approx(length, rel=1e-12)
    assert spec.length == length
    assert {e.length for e in spec.edges} == {length / len(spec.edges)}
    assert sorted(spec.edge_starts.values()) == pytest.approx(
        [i * length / len(spec.edges) for i in range(len(spec.edges))]
    )
    for first, route in spec.routes.items():  # each route is one lap from its first edge
        assert route[0] == first
        assert sorted(route) == sorted(e.id for e in spec.edges)


def test_long_rings_are_cut_into_more_edges() -> None:
    assert ring_edge_count(230.0) == 4
    assert ring_edge_count(2300.0) == 4
    assert ring_edge_count(2300.5) == 8
    assert ring_edge_count(23000.0) == 40
    assert [e.id for e in ring_spec(230.0, 1, 30.0, 40).edges] == [
        "bottom",
        "right",
        "top",
        "left",
    ]


def net_lanes(net_file: Path) -> dict[str, list[float]]:
    root = ET.parse(net_file).getroot()
    return {
        e.get("id", ""): [float(lane.get("length", "nan")) for lane in e.iter("lane")]
        for e in root.iter("edge")
        if e.get("function") != "internal"
    }


@pytest.mark.parametrize(("length", "lanes"), [(230.0, 1), (230.3, 2), (23000.0, 1)])
def test_netconvert_keeps_the_forced_edge_lengths(
    tmp_path: Path, length: float, lanes: int
) -> None:
    spec = ring_spec(length, lanes, 30.0, 40)
    net = build_network(spec, tmp_path, name="ring")
    found = net_lanes(net)
    assert sorted(found) == sorted(e.id for e in spec.edges)
    for edge_lanes in found.values():
        assert len(edge_lanes) == lanes
    assert sum(v[0] for v in found.values()) == pytest.approx(length, abs=1e-5)
    assert build_network(spec, tmp_path, name="ring") == net  # cached, not rebuilt


def test_edge_xml_forces_lengths_and_speeds() -> None:
    text = edges_xml(ring_spec(230.0, 2, 25.0, 5))
    assert text.count("<edge ") == 4
    assert 'length="57.500000000"' in text
    assert 'numLanes="2"' in text
    assert 'speed="25.000000"' in text


def test_netconvert_failure_shows_netconverts_own_message(tmp_path: Path) -> None:
    spec = ring_spec(230.0, 1, 30.0, 40)
    broken = dataclasses.replace(spec, nodes=spec.nodes[:3])  # edges still use node 'left'
    with pytest.raises(SimulationError, match="netconvert failed") as err:
        build_network(broken, tmp_path)
    assert "'left' is not known" in str(err.value)
    assert not list(tmp_path.glob("*.net.xml"))
