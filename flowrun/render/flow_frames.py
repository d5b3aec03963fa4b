"""Flow's ``PygletRenderer``: top-down frames for vision-based agents, drawn without a display.

Flow's renderer (``flow.renderer.pyglet_renderer``) draws the lanes as lines and each car as a
small triangle pointing along its SUMO angle, in an OpenGL window; its frames feed policies that
learn from pixels. This one draws the same picture with PIL into an array, so it runs headless
and needs no OpenGL: the same constructor and ``render`` / ``get_sight`` / ``close`` methods,
the same frame geometry (``pxpm`` pixels per metre, a margin of ``sight_radius`` m around the
lanes, Flow's 2 m shift and ``(n - 4) / n`` scale of each axis), Flow's colours per mode:

- ``rgb``: humans green, AVs blue; ``drgb``: shaded by each car's ``dynamics`` value in [0, 1]
  (humans greens, AVs blues);
- ``gray`` / ``dgray``: the same in grey levels, one channel.

Lanes are light grey on a dark background; with ``show_radius`` each AV gets a circle of
``sight_radius`` m. ``save_render`` keeps every call's input and ``close`` writes them with
the network as Flow's ``data_<n>.npy`` (``[network, [human_orientations, ...], ...]``) and a
PNG per frame.
"""

from __future__ import annotations

import ctypes
import math
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from PIL import Image, ImageDraw

RGB = npt.NDArray[np.uint8]
MODES = ("rgb", "drgb", "gray", "dgray")
BACKGROUND = (32, 32, 32)
LANE = (224, 224, 224)
#: (low, high) colour of the dynamic modes' shading, humans then AVs
_SHADES = {
    "drgb": (((199, 233, 192), (35, 139, 69)), ((198, 219, 239), (33, 113, 181))),
    "dgray": (((115, 115, 115), (13, 13, 13)), ((242, 242, 242), (140, 140, 140))),
}
#: fixed colours of the static modes, humans then AVs
_FIXED = {"rgb": ((0, 225, 0), (0, 150, 200)), "gray": ((100, 100, 100), (150, 150, 150))}
CAR_SIZE = 5.0  # m, length of a car's triangle


class RendererClosedError(RuntimeError, ctypes.ArgumentError):
    """``render`` after ``close``. Also a ``ctypes.ArgumentError``, which is what Flow's
    OpenGL renderer raises then, so Flow code that catches it keeps working."""


def _axis(values: npt.NDArray[np.float64], margin: float, pxpm: float) -> tuple[int, float, float]:
    """Flow's frame along one axis: (pixels, shift, scale) for the lane coordinates ``values``."""
    extent = int(values.max() - values.min())
    scale = (extent - 4) / extent if extent > 4 else 1.0
    return int((extent + 2 * margin) * pxpm), float(values.min() - 2 - margin), scale


class PygletRenderer:
    """Flow's ``PygletRenderer(network, mode, save_render, path, sight_radius, show_radius,
    pxpm, alpha)``; see the module docstring.

    Args:
        network: the lanes, each a flat list ``[x0, y0, x1, y1, ...]`` in metres.
        mode: ``rgb``, ``drgb``, ``gray`` or ``dgray``.
        save_render: keep every frame's input (and a PNG of it) for :meth:`close` to save.
        path: folder for the saved data (a time-stamped subfolder is made in it).
        sight_radius: what an agent sees around it, m; also the frame's margin.
        show_radius: draw each AV's sight circle.
        pxpm: pixels per metre.
        alpha: opacity of cars and lanes (blended over the background).

    Raises:
        ValueError: an unknown mode (Flow's error type).
    """

    def __init__(
        self,
        network: Sequence[Sequence[float]],
        mode: str,
        save_render: bool = False,
        path: str = os.path.expanduser("~") + "/flow_rendering",
        sight_radius: float = 50,
        show_radius: bool = False,
        pxpm: float = 2,
        alpha: float = 1.0,
    ) -> None:
        if mode not in MODES:
            raise ValueError(f"mode {mode!r} is not supported; expected one of {MODES}")
        self.mode, self.save_render, self.sight_radius = mode, save_render, sight_radius
        self.show_radius, self.pxpm, self.alpha = show_radius, pxpm, alpha
        self.path = os.path.join(path, time.strftime("%Y-%m-%d-%H%M%S"))
        self.data: list[Any] = [network]
        self.time = 0
        points = np.array([p for lane in network for p in lane], dtype=np.float64)
        self.width, self.x_shift, self.x_scale = _axis(points[::2], sight_radius, pxpm)
        self.height, self.y_shift, self.y_scale = _axis(points[1::2], sight_radius, pxpm)
        self.lane_polys = [self._px(np.asarray(lane, dtype=np.float64)) for lane in network]
        self.frame: RGB = np.zeros((self.height, self.width, 3), np.uint8)
        self._closed = False

    def _px(self, flat: npt.NDArray[np.float64]) -> list[tuple[float, float]]:
        """Pixel points (y down) of a flat ``[x0, y0, ...]`` list of map points."""
        x = (flat[::2] - self.x_shift) * self.x_scale * self.pxpm
        y = self.height - (flat[1::2] - self.y_shift) * self.y_scale * self.pxpm
        return list(zip(x.tolist(), y.tolist(), strict=True))

    def _colours(self, dynamics: Sequence[float], machine: bool) -> list[tuple[int, ...]]:
        if self.mode in _FIXED:
            return [_FIXED[self.mode][machine]] * len(dynamics)
        low, high = (np.array(c, dtype=np.float64) for c in _SHADES[self.mode][machine])
        d = np.clip(np.asarray(dynamics, dtype=np.float64), 0.0, 1.0)[:, None]
        return [tuple(int(v) for v in row) for row in np.rint(low + d * (high - low))]

    def render(
        self,
        human_orientations: Sequence[Sequence[float]],
        machine_orientations: Sequence[Sequence[float]],
        human_dynamics: Sequence[float],
        machine_dynamics: Sequence[float],
        human_logs: Sequence[Any],
        machine_logs: Sequence[Any],
    ) -> RGB:
        """One frame: ``(height, width, 3)`` (``rgb``/``drgb``) or ``(height, width)``.

        Orientations are ``[x, y, angle]`` per car (m, SUMO's angle in degrees: 0 north,
        clockwise); dynamics a value in [0, 1] per car (e.g. speed / max speed) for the
        dynamic modes; logs Flow's ``[time, step, id]`` per car (kept when saving).

        Raises:
            RendererClosedError: the renderer was closed.
        """
        if self._closed:
            raise RendererClosedError("the renderer is closed; make a new PygletRenderer")
        self.time += 1
        image = Image.new("RGB", (self.width, self.height), BACKGROUND)
        draw = ImageDraw.Draw(image)
        for poly in self.lane_polys:
            draw.line(poly, fill=self._blend(LANE), width=max(1, round(self.pxpm)))
        self._cars(draw, human_orientations, self._colours(human_dynamics, False), 0.0)
        radius = self.sight_radius if self.show_radius else 0.0
        self._cars(draw, machine_orientations, self._colours(machine_dynamics, True), radius)
        self.frame = np.asarray(image, dtype=np.uint8)
        if self.save_render:
            Path(self.path).mkdir(parents=True, exist_ok=True)
            image.save(os.path.join(self.path, f"frame_{self.time:06d}.png"))
            self.data.append([list(human_orientations), list(machine_orientations),
                              list(human_dynamics), list(machine_dynamics),
                              list(human_logs), list(machine_logs)])  # fmt: skip
        return self.frame[:, :, 0] if "gray" in self.mode else self.frame

    def _blend(self, colour: Sequence[int]) -> tuple[int, int, int]:
        a = self.alpha
        r, g, b = (round(a * c + (1 - a) * k) for c, k in zip(colour, BACKGROUND, strict=True))
        return r, g, b

    def _cars(self, draw: ImageDraw.ImageDraw, orientations: Sequence[Sequence[float]],
              colours: Sequence[Sequence[int]], radius: float) -> None:  # fmt: skip
        """Each car a triangle with its tip at the car, ``CAR_SIZE`` m long, a quarter of that
        wide at the back (Flow's shape); a circle of ``radius`` m around it when given."""
        s = CAR_SIZE * self.pxpm
        for (x, y, angle), colour in zip(orientations, colours, strict=False):
            ((px, py),) = self._px(np.array([x, y], dtype=np.float64))
            a = math.radians(angle)
            bx, by = px - s * self.x_scale * math.sin(a), py + s * self.y_scale * math.cos(a)
            wx, wy = 0.25 * s * self.x_scale * math.cos(a), 0.25 * s * self.y_scale * math.sin(a)
            fill = self._blend(colour)
            draw.polygon([(px, py), (bx + wx, by + wy), (bx - wx, by - wy)], fill=fill)
            if radius > 0:
                r = radius * self.pxpm
                draw.ellipse([px - r, py - r, px + r, py + r], outline=fill)

    def get_sight(self, orientation: Sequence[float], veh_id: str) -> RGB:
        """What the car at ``orientation`` (``[x, y, angle]``) sees in the last frame: the
        square of ``2 * sight_radius`` m around it, outside the circle blacked out, turned by
        its angle (``(n, n, 3)``, one channel in the gray modes). ``veh_id`` names the PNG
        written when saving."""
        x, y, angle = orientation
        ((px, py),) = self._px(np.array([x, y], dtype=np.float64))
        r = int(self.sight_radius * self.pxpm)
        padded = np.pad(self.frame, ((r, r), (r, r), (0, 0)))
        cx, cy = int(px) + r, int(py) + r
        square = padded[cy - r : cy + r, cx - r : cx + r].copy()
        yy, xx = np.mgrid[0 : 2 * r, 0 : 2 * r]
        square[(xx - r) ** 2 + (yy - r) ** 2 > r * r] = 0
        sight = np.asarray(Image.fromarray(square).rotate(angle), dtype=np.uint8)
        if self.save_render:
            Path(self.path).mkdir(parents=True, exist_ok=True)
            name = f"sight_{veh_id}_{self.time:06d}.png"
            Image.fromarray(sight).save(os.path.join(self.path, name))
        return sight[:, :, 0] if "gray" in self.mode else sight

    def close(self) -> str:
        """End the renderer; with ``save_render``, write the kept data and return its path
        (``<path>/<time>/data_<frames>.npy``), else ``""``."""
        self._closed = True
        if not self.save_render:
            return ""
        Path(self.path).mkdir(parents=True, exist_ok=True)
        out = os.path.join(self.path, f"data_{self.time:06d}.npy")
        data = np.empty(len(self.data), dtype=object)
        for i, item in enumerate(self.data):
            data[i] = item
        np.save(out, data, allow_pickle=True)
        return out
