"""A top-down picture of a ring: cars coloured by speed, RL cars outlined (no display needed)."""

from __future__ import annotations

import math

import numpy as np
from PIL import Image, ImageDraw

from flowrun.kernel import Kernel

SIZE = 400


def speed_colour(speed: float, v_max: float) -> tuple[int, int, int]:
    """Red (stopped) through yellow to green (``v_max`` or faster)."""
    f = min(max(speed / v_max, 0.0), 1.0) if v_max > 0 else 0.0
    if f < 0.5:
        return 220, int(40 + 400 * f), 40
    return int(220 - 400 * (f - 0.5)), 220, 40


def render_ring(k: Kernel, size: int = SIZE) -> np.ndarray:
    """RGB array ``(size, size, 3)`` of the ring with every car drawn at its ring position."""
    spec = k.network.spec
    img = Image.new("RGB", (size, size), (245, 245, 245))
    draw = ImageDraw.Draw(img)
    c = size / 2
    radius = size * 0.4
    lanes = max(e.lanes for e in spec.edges)
    lane_w = max(6.0, size * 0.03)
    outer = radius + lanes * lane_w / 2
    inner = radius - lanes * lane_w / 2
    draw.ellipse([c - outer, c - outer, c + outer, c + outer], fill=(90, 90, 90))
    draw.ellipse([c - inner, c - inner, c + inner, c + inner], fill=(245, 245, 245))
    vk = k.vehicle
    v_max = k.network.max_speed()
    for i in range(vk.table.size):
        theta = -math.pi / 2 + 2 * math.pi * float(vk.position[i]) / spec.length
        r = inner + (int(vk.lanes[i]) + 0.5) * lane_w
        x, y = c + r * math.cos(theta), c - r * math.sin(theta)
        half = lane_w * 0.45
        rl = bool(vk.table.is_rl[i])
        draw.ellipse(
            [x - half, y - half, x + half, y + half],
            fill=speed_colour(float(vk.speed[i]), v_max),
            outline=(30, 60, 230) if rl else None,
            width=3 if rl else 1,
        )
    draw.text((8, 8), f"t = {k.simulation.time:.1f} s", fill=(0, 0, 0))
    return np.asarray(img, dtype=np.uint8)
