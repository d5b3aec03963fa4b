"""Initial placement of vehicles along a closed road (Flow's ``InitialConfig`` semantics)."""

from __future__ import annotations

import math

import numpy as np

from flowrun.config.params import InitialConfig


def place_on_closed_road(
    length: float,
    lanes: int,
    vehicle_lengths: list[float],
    initial: InitialConfig,
    rng: np.random.Generator,
) -> tuple[list[float], list[int]]:
    """Positions (front bumper, metres along the road) and lanes of each vehicle.

    ``uniform``: cars fill ``length - bunching`` metres evenly starting at ``x0``, cycling
    over ``min(lanes, lanes_distribution)`` lanes; each position then gets a Gaussian offset
    of std ``perturbation``. ``random``: the free road is split at uniform random points.
    ``shuffle`` permutes which vehicle takes which slot. All draws come from ``rng``.

    Args:
        length: road length, m.
        lanes: number of lanes.
        vehicle_lengths: length of each vehicle, m, in placement order.
        initial: the placement settings.
        rng: the seeded generator.

    Returns:
        positions (wrapped into ``[0, length)``) and lane indices.
    """
    n = len(vehicle_lengths)
    if n == 0:
        return [], []
    k = int(max(1, min(lanes, initial.lanes_distribution)))
    per_lane = math.ceil(n / k)
    available = length - initial.bunching
    slot = np.arange(n) // k
    lane = (np.arange(n) % k).astype(int)
    if initial.spacing == "random":
        unit = max(vehicle_lengths) + initial.min_gap
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
