"""Initial placement of vehicles (Flow's ``InitialConfig`` semantics): on a closed ring, and
on any network as rows along its edges laid end to end."""

from __future__ import annotations

import itertools
import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from flowrun.config.params import InitialConfig, VehicleParams
from flowrun.errors import ConfigError, CountMismatchError
from flowrun.networks.flow_line import flow_loop_line, place_on_flow_line
from flowrun.networks.placement_rules import lanes_spread, no_room
from flowrun.networks.spec import NetworkSpec, StartPositions
from flowrun.suggest import did_you_mean

log = logging.getLogger(__name__)


def place_on_closed_road(
    length: float,
    lanes: int,
    vehicle_space: list[float],
    initial: InitialConfig,
    rng: np.random.Generator,
) -> tuple[list[float], list[int]]:
    """Positions (front bumper, metres along the road) and lanes of each vehicle.

    ``uniform``: cars fill ``length - bunching`` metres evenly starting at ``x0``, cycling
    over ``min(lanes, lanes_distribution)`` lanes; each position then gets a Gaussian offset
    of std ``perturbation``. ``random``: the free road is split at uniform random points, so
    no two cars are closer than ``unit = max(vehicle_space) + min_gap`` front to front.
    ``shuffle`` permutes which vehicle takes which slot. All draws come from ``rng``.

    ``initial.min_gap`` is Flow's: the extra bumper-to-bumper gap every placement keeps. With
    ``uniform`` spacing it does not move the cars (Flow spreads them evenly whatever it is) but
    the spacing must leave it, as in Flow, which refuses a ring where it does not.

    Args:
        length: road length, m.
        lanes: number of lanes.
        vehicle_space: each vehicle's length plus its SUMO ``minGap``, m, in placement order
            (SUMO refuses to insert a car closer than that behind another).
        initial: the placement settings.
        rng: the seeded generator.

    Returns:
        positions (wrapped into ``[0, length)``) and lane indices.

    Raises:
        ConfigError: the cars do not fit with ``min_gap`` (key path ``min_gap``).
    """
    n = len(vehicle_space)
    if n == 0:
        return [], []
    k = int(min(lanes, lanes_spread(initial.lanes_distribution)))
    per_lane = math.ceil(n / k)
    available = length - initial.bunching
    slot = np.arange(n) // k
    lane = (np.arange(n) % k).astype(int)
    unit = max(vehicle_space) + max(0.0, initial.min_gap)
    if per_lane > 1 and available / per_lane < unit:
        raise ConfigError(
            f"{per_lane} vehicles per lane need {unit:.1f} m each (length + minGap + min_gap "
            f"{initial.min_gap:g}) but the ring offers {available / per_lane:.1f} m per vehicle; "
            "use a smaller min_gap, fewer vehicles or less bunching",
            path="min_gap",
        )
    if initial.spacing == "random":
        free = max(available - per_lane * unit, 0.0)
        offsets = np.sort(rng.uniform(0.0, free, size=(k, per_lane)), axis=1)
        pos = initial.x0 + slot * unit + offsets[lane, slot]
    else:
        spacing = available / per_lane
        pos = initial.x0 + slot * spacing
        if initial.perturbation > 0:
            pos = pos + rng.normal(0.0, initial.perturbation, size=n)
    order = rng.permutation(n) if initial.shuffle else np.arange(n)
    positions = np.mod(pos[order], length)
    return [float(x) for x in positions], [int(x) for x in lane[order]]


SPACINGS = ("uniform", "random")


@dataclass(frozen=True)
class PlacementEdge:
    """An edge cars may start on.

    Attributes:
        id: edge id.
        length: edge length, m.
        lanes: number of lanes.
        joined: a route drives onto this edge straight from the one before it in the
            placement order, with as many lanes (so uniform rows may run on across the
            junction; otherwise fronts keep one car's space from the edge's start).
    """

    id: str
    length: float
    lanes: int
    joined: bool = False


def place_on_network(
    spec: NetworkSpec,
    vehicle_space: list[float],
    initial: InitialConfig,
    rng: np.random.Generator,
) -> StartPositions:
    """Flow's ``InitialConfig`` placement on any network (open roads, junctions, many edges).

    The edges of ``initial.edges_distribution`` are laid end to end: ``"all"`` is every
    non-internal edge a route starts on (every non-internal edge when the network has no
    routes) in the order of their starts along the network; a list names edges in order; a
    dict edge -> count places that many cars on each edge, edge by edge in the dict's order.
    Where a route drives from one edge straight onto the next one in that order (same lane
    count), uniform rows run on across the junction; elsewhere a car's front keeps
    ``unit = max(vehicle_space) + min_gap`` from the edge's start, so no car hangs back onto
    a road it is not driving on. See :func:`place_on_edges`. ``uniform`` over ``all`` edges of
    a loop whose junction links lie on Flow's line (the figure eight) is Flow's own rule
    instead: :func:`flowrun.networks.flow_line.place_on_flow_line`.

    Args:
        spec: the network.
        vehicle_space: each vehicle's length plus its SUMO ``minGap``, m, in placement order.
        initial: the placement settings.
        rng: the seeded generator.

    Raises:
        ConfigError: unknown edge, counts that do not match, unknown spacing, or not enough room.
    """
    by_id = {e.id: e for e in spec.edges}
    distribution = initial.edges_distribution
    if distribution == "all" and initial.spacing == "uniform":

        line = flow_loop_line(spec)
        if line is not None:
            return place_on_flow_line(spec, line, vehicle_space, initial, rng)
    if isinstance(distribution, dict):
        total = sum(int(v) for v in distribution.values())
        if total != len(vehicle_space):
            raise CountMismatchError(
                f"edges_distribution places {total} vehicles but the vehicles section has "
                f"{len(vehicle_space)}; make the counts add up",
                path="edges_distribution",
            )
        parts = [_resolve_edges(spec, [edge], by_id) for edge in distribution]
        counts = [int(v) for v in distribution.values()]
    else:
        parts = [_resolve_edges(spec, distribution, by_id)]
        counts = [len(vehicle_space)]
    edges: list[str] = []
    lane_pos: list[float] = []
    lanes: list[int] = []
    first = 0
    for part, count in zip(parts, counts, strict=True):
        placed = place_on_edges(part, vehicle_space[first : first + count], initial, rng)
        first += count
        edges += placed.edges
        lane_pos += placed.lane_pos
        lanes += placed.lanes
    return StartPositions(edges, lane_pos, lanes)


def _resolve_edges(
    spec: NetworkSpec, distribution: str | list[str], by_id: dict[str, Any]
) -> list[PlacementEdge]:
    if distribution == "all":
        plain = [e for e in spec.edges if not e.id.startswith(":")]
        routed = [e for e in plain if spec.choices(e.id)] or plain
        names = [e.id for e in sorted(routed, key=lambda e: spec.edge_starts.get(e.id, math.inf))]
    elif isinstance(distribution, str):
        raise ConfigError(
            f"expected 'all', a list of edge names or a dict edge -> count, got {distribution!r}",
            path="edges_distribution",
        )
    else:
        names = list(distribution)
    for name in names:
        if name not in by_id or name.startswith(":"):
            plain_ids = [e.id for e in spec.edges if not e.id.startswith(":")]
            raise ConfigError(
                f"no edge '{name}' to place vehicles on{did_you_mean(str(name), plain_ids)}; "
                f"the network's edges are: {', '.join(plain_ids)}",
                path="edges_distribution",
            )
    routes = [*spec.routes.values()]
    routes += [route for options in spec.route_choices.values() for route, _ in options]
    follows = {pair for route in routes for pair in itertools.pairwise(route)}
    return [
        PlacementEdge(
            name,
            float(by_id[name].length),
            int(by_id[name].lanes),
            (names[i - 1], name) in follows and by_id[names[i - 1]].lanes == by_id[name].lanes,
        )
        for i, name in enumerate(names)
    ]


def place_on_edges(
    edges: list[PlacementEdge],
    vehicle_space: list[float],
    initial: InitialConfig,
    rng: np.random.Generator,
) -> StartPositions:
    """Place vehicles on ``edges`` laid end to end (Flow's uniform / random spacing).

    Fronts keep ``unit = max(vehicle_space) + min_gap`` metres from the start of each edge
    that is not ``joined`` (and of every edge with ``random`` spacing); cars are spread over
    ``min(lanes, lanes_distribution)`` lanes. ``uniform``: rows of side-by-side cars (one per
    lane) every ``(usable length - bunching) / rows`` metres from ``x0`` (wrapping), with the
    fewest rows that hold every car, then each car shifted by a Gaussian of std
    ``perturbation`` (kept on its edge). ``random``: Flow's random gaps, lane 0 of each edge
    first; ``x0`` is not used. ``shuffle`` permutes which vehicle takes which slot. Negative
    ``bunching`` and ``min_gap`` count as 0.

    Raises:
        ConfigError: spacing not ``uniform``/``random``, or not enough room.
    """
    n = len(vehicle_space)
    if initial.spacing not in SPACINGS:
        raise ConfigError(
            f"unknown spacing {initial.spacing!r}{did_you_mean(str(initial.spacing), SPACINGS)}; "
            f"expected one of: {', '.join(SPACINGS)}",
            path="spacing",
        )
    if n == 0:
        return StartPositions([], [], [])
    unit = max(vehicle_space) + max(0.0, initial.min_gap)
    bunching = max(0.0, initial.bunching)
    usable = [e for e in edges if e.length >= unit]
    spread = lanes_spread(initial.lanes_distribution)
    lanes = np.array([int(min(e.lanes, spread)) for e in usable], dtype=np.int64)
    uniform = initial.spacing == "uniform"
    lead = np.array([0.0 if uniform and e.joined else unit for e in usable], dtype=np.float64)
    room = np.array([e.length for e in usable], dtype=np.float64) - lead
    if not uniform:
        edge_idx, offset, lane = _random_slots(room, lanes, n, unit, bunching, rng)
    else:
        edge_idx, offset, lane = _uniform_slots(room, lanes, n, unit, bunching, initial.x0)
        if initial.perturbation > 0:
            noisy = offset + rng.normal(0.0, initial.perturbation, size=n)
            offset = np.clip(noisy, 0.0, room[edge_idx])
    order = rng.permutation(n) if initial.shuffle else np.arange(n)
    return StartPositions(
        [usable[int(i)].id for i in edge_idx[order]],
        [float(x) for x in (lead[edge_idx] + offset)[order]],
        [int(x) for x in lane[order]],
    )


def _uniform_slots(
    room: np.ndarray, lanes: np.ndarray, n: int, unit: float, bunching: float, x0: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    total = float(room.sum())
    span = total - bunching
    if room.size == 0 or span <= 0:
        raise no_room(n, unit, max(total, 0.0), bunching)
    starts = np.concatenate(([0.0], np.cumsum(room)[:-1]))
    rows = math.ceil(n / int(lanes.max()))
    while True:
        step = span / rows
        x = np.mod(x0 + np.arange(rows) * step, total)
        idx = np.clip(np.searchsorted(starts, x, side="right") - 1, 0, room.size - 1)
        if int(lanes[idx].sum()) >= n:
            break
        rows += 1
    if rows > 1 and step < unit:
        raise no_room(n, unit, span, bunching)
    per_row = lanes[idx]
    row_of = np.repeat(np.arange(rows), per_row)[:n]
    lane = (np.arange(n) - np.repeat(np.cumsum(per_row) - per_row, per_row)[:n]).astype(np.int64)
    edge_idx = idx[row_of]
    offset = np.minimum(x[row_of] - starts[edge_idx], room[edge_idx])
    return edge_idx, offset, lane


def _random_slots(
    room: np.ndarray,
    lanes: np.ndarray,
    n: int,
    unit: float,
    bunching: float,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    seg_edge = np.repeat(np.arange(room.size), lanes)
    seg_lane = np.concatenate([np.arange(k) for k in lanes]) if room.size else seg_edge
    seg_room = room[seg_edge]
    total = float(seg_room.sum())
    free = total - (n - 1) * unit - bunching * (int(lanes.max()) if room.size else 1)
    if room.size == 0 or free <= 0:
        raise no_room(n, unit, max(total, 0.0), bunching)
    y = np.sort(rng.uniform(0.0, free, size=n)) + np.arange(n) * unit
    seg_start = np.concatenate(([0.0], np.cumsum(seg_room)[:-1]))
    seg = np.clip(np.searchsorted(seg_start, y, side="right") - 1, 0, seg_room.size - 1)
    offset = np.minimum(y - seg_start[seg], seg_room[seg])
    return seg_edge[seg], offset, seg_lane[seg].astype(np.int64)


def vehicle_space(vehicles: VehicleParams) -> list[float]:
    """Length plus SUMO ``minGap`` of every vehicle, m, in ``VehicleParams.ids`` order."""
    return [
        g.car_following_params.length + g.car_following_params.min_gap
        for g in vehicles.groups
        for _ in range(g.num_vehicles)
    ]
