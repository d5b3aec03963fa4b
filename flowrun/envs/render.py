"""A top-down picture of a ring: cars coloured by speed, RL cars outlined (no display needed)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw

from flowrun.kernel import Kernel

SIZE = 400
BACKGROUND = (245, 245, 245)
ROAD = (90, 90, 90)
RL_OUTLINE = (30, 60, 230)


def speed_colour(speed: float, v_max: float) -> tuple[int, int, int]:
    """Red (stopped) through yellow to green (``v_max`` or faster)."""
    f = min(max(speed / v_max, 0.0), 1.0) if v_max > 0 else 0.0
    if f < 0.5:
        return 220, int(40 + 400 * f), 40
    return int(220 - 400 * (f - 0.5)), 220, 40


@dataclass(frozen=True)
class RingLayout:
    """Where the ring and its cars are drawn, in pixels (x right, y down).

    Attributes:
        centre: the ring's centre (x and y).
        inner: inner radius of the road.
        outer: outer radius of the road.
        lane_width: width of one lane.
        cars: ``(n, 2)`` centre of every car, in the kernel's vehicle order.
    """

    centre: float
    inner: float
    outer: float
    lane_width: float
    cars: np.ndarray

    @property
    def car_radius(self) -> float:
        """Radius of the disc drawn for a car."""
        return self.lane_width * 0.45


def ring_layout(k: Kernel, size: int = SIZE) -> RingLayout:
    """The geometry of :func:`render_ring`: position 0 at the bottom, driving anticlockwise."""
    spec = k.network.spec
    c = size / 2
    radius = size * 0.4
    lanes = max(e.lanes for e in spec.edges)
    lane_w = max(6.0, size * 0.03)
    inner = radius - lanes * lane_w / 2
    vk = k.vehicle
    theta = -math.pi / 2 + 2 * math.pi * np.asarray(vk.position, dtype=np.float64) / spec.length
    r = inner + (np.asarray(vk.lanes, dtype=np.float64) + 0.5) * lane_w
    cars = np.stack([c + r * np.cos(theta), c - r * np.sin(theta)], axis=-1).reshape(-1, 2)
    return RingLayout(c, inner, radius + lanes * lane_w / 2, lane_w, cars)


def render_ring(k: Kernel, size: int = SIZE) -> np.ndarray:
    """RGB array ``(size, size, 3)`` of the ring with every car drawn at its ring position."""
    layout = ring_layout(k, size)
    img = Image.new("RGB", (size, size), BACKGROUND)
    draw = ImageDraw.Draw(img)
    c, outer, inner = layout.centre, layout.outer, layout.inner
    draw.ellipse([c - outer, c - outer, c + outer, c + outer], fill=ROAD)
    draw.ellipse([c - inner, c - inner, c + inner, c + inner], fill=BACKGROUND)
    vk = k.vehicle
    v_max = k.network.max_speed()
    half = layout.car_radius
    for i, (x, y) in enumerate(layout.cars.tolist()):
        rl = bool(vk.table.is_rl[i])
        draw.ellipse(
            [x - half, y - half, x + half, y + half],
            fill=speed_colour(float(vk.speed[i]), v_max),
            outline=RL_OUTLINE if rl else None,
            width=3 if rl else 1,
        )
    draw.text((8, 8), f"t = {k.simulation.time:.1f} s", fill=(0, 0, 0))
    return np.asarray(img, dtype=np.uint8)
