"""Flow's uniform placement on a loop whose junction links lie on Flow's notional line (the
figure eight): :func:`flow_loop_line` recognises such a network, :func:`place_on_flow_line`
places the cars as Flow's ``gen_even_start_pos`` does."""

from __future__ import annotations

import bisect
import itertools
import math

import numpy as np

from flowrun.config.params import InitialConfig
from flowrun.networks.placement_rules import lanes_spread, no_room
from flowrun.networks.spec import NetworkSpec, StartPositions


def flow_loop_line(spec: NetworkSpec) -> list[tuple[float, str]] | None:
    """Flow's notional line through a loop whose junction links are laid out on it.

    ``(start, edge)`` sorted by start, internal edges included, when the network lists the
    starts of its junction-internal edges, every plain edge has one and the same lane count,
    and its routes drive the plain edges round in the order of their starts (the figure
    eight); ``None`` otherwise.
    """
    plain = [e for e in spec.edges if not e.id.startswith(":")]
    starts = spec.edge_starts
    if not any(e.startswith(":") for e in starts) or any(e.id not in starts for e in plain):
        return None
    if len({e.lanes for e in plain}) != 1:
        return None
    order = sorted(plain, key=lambda e: starts[e.id])
    routes = [*spec.routes.values()]
    routes += [route for options in spec.route_choices.values() for route, _ in options]
    follows = {pair for route in routes for pair in itertools.pairwise(route)}
    loop = zip(order, order[1:] + order[:1], strict=True)
    if not all((a.id, b.id) in follows for a, b in loop):
        return None
    return sorted((float(x), e) for e, x in starts.items())


def place_on_flow_line(
    spec: NetworkSpec,
    line: list[tuple[float, str]],
    vehicle_space: list[float],
    initial: InitialConfig,
    rng: np.random.Generator,
) -> StartPositions:
    """Flow's uniform placement on a loop with junction links (``gen_even_start_pos``).

    Each lane keeps a cursor along the line, starting at ``x0`` and advancing by
    ``(length - bunching) / ceil(n / lanes)`` per car, ``length`` being where the last plain
    edge ends plus the link before the first one (Flow's own junction lengths). A car whose
    cursor falls on a junction-internal edge starts at the beginning of the edge after it
    instead, and that lane's cursor moves there too. Cars take the lanes in turn.
    ``perturbation`` then shifts each car along its edge (kept on it); ``shuffle`` permutes
    which vehicle takes which slot.

    Raises:
        ConfigError: the cars would be closer than one car's length plus its minGap.
    """
    n = len(vehicle_space)
    if n == 0:
        return StartPositions([], [], [])
    by_id = {e.id: e for e in spec.edges}
    plain = [(x, e) for x, e in line if not e.startswith(":")]
    # Flow's length of the line: to the end of the last edge, plus the junction link before
    # the first one (where the line starts over)
    total = max(x + float(by_id[e].length) for x, e in plain) + min(x for x, _ in plain)
    lanes_per_edge = by_id[plain[0][1]].lanes
    k = int(min(lanes_per_edge, lanes_spread(initial.lanes_distribution)))
    bunching = max(0.0, initial.bunching)
    step = (total - bunching) / math.ceil(n / k)
    unit = max(vehicle_space) + max(0.0, initial.min_gap)
    if n > k and step < unit:
        raise no_room(n, unit, total - bunching, bunching)
    starts = [x for x, _ in line]
    cursor = [float(initial.x0) % total] * k
    edges: list[str] = []
    offsets: list[float] = []
    for i in range(n):
        lane = i % k
        at = max(bisect.bisect_right(starts, cursor[lane]) - 1, 0)
        while line[at][1].startswith(":"):  # not on a junction: the next edge's start
            at = (at + 1) % len(line)
            cursor[lane] = line[at][0]
        edges.append(line[at][1])
        offsets.append(cursor[lane] - line[at][0])
        cursor[lane] = (cursor[lane] + step) % total
    pos = np.array(offsets)
    if initial.perturbation > 0:
        room = np.array([float(by_id[e].length) for e in edges])
        pos = np.clip(pos + rng.normal(0.0, initial.perturbation, size=n), 0.0, room)
    order = rng.permutation(n) if initial.shuffle else np.arange(n)
    lanes = [i % k for i in range(n)]
    return StartPositions(
        [edges[i] for i in order], [float(pos[i]) for i in order], [lanes[i] for i in order]
    )
