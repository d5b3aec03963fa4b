"""Speed colours on a scale that fits the run, and traffic-light colours (shared by every
picture: the raster frames, the HTML player and the Foxglove scene)."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

#: Red (stopped) through yellow to green (the top of the scale), 5 stops.
SPEED_STOPS = np.array(
    [(215, 48, 39), (252, 141, 89), (254, 224, 139), (145, 207, 96), (26, 152, 80)],
    dtype=np.float64,
)
#: Outline of cars driven by the RL agent (AVs).
AV_COLOUR = (37, 99, 235)
#: Colour of a SUMO signal state character; anything else (off, unknown) is grey.
SIGNAL_COLOURS = {
    "G": (0, 180, 0),
    "g": (0, 180, 0),
    "y": (250, 200, 0),
    "Y": (250, 200, 0),
    "u": (250, 140, 0),
    "r": (220, 0, 0),
    "R": (220, 0, 0),
    "s": (150, 0, 150),
}
SIGNAL_OFF = (140, 140, 140)


def speed_top(max_speed: float) -> float:
    """The top of a speed scale for a run whose fastest car drove ``max_speed`` m/s: the next
    of 1, 1.5, 2, 2.5, 3, 4, 5, 6, 8 (times a power of ten) at or above it, at least 1 m/s."""
    if not math.isfinite(max_speed) or max_speed <= 1.0:
        return 1.0
    power = 10.0 ** math.floor(math.log10(max_speed))
    for step in (1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0):
        if step * power >= max_speed - 1e-9:
            return step * power
    return 10.0 * power  # pragma: no cover - the loop always returns


def speed_colours(speed: npt.ArrayLike, top: float) -> npt.NDArray[np.uint8]:
    """``(n, 3)`` RGB colours of speeds (m/s) on a scale from 0 to ``top`` (clipped)."""
    f = np.clip(np.nan_to_num(np.asarray(speed, dtype=np.float64) / top), 0.0, 1.0)
    pos = f * (len(SPEED_STOPS) - 1)
    i = np.minimum(pos.astype(np.int64), len(SPEED_STOPS) - 2)
    w = (pos - i)[:, None]
    rgb = SPEED_STOPS[i] * (1 - w) + SPEED_STOPS[i + 1] * w
    return np.rint(rgb).astype(np.uint8)


def signal_colour(state: str) -> tuple[int, int, int]:
    """Colour of one character of a SUMO signal state string."""
    return SIGNAL_COLOURS.get(state, SIGNAL_OFF)
