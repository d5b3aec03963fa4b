"""Filling many small shapes into an RGB array (numpy, no drawing library per frame).

Cars are stamped from pixel masks made once per size and heading step (:class:`CarStamps`);
signal heads are discs filled in one vectorised pass (:func:`fill_discs`).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from flowrun.types import FloatArray

RGB = npt.NDArray[np.uint8]
BoolMask = npt.NDArray[np.bool_]
MAX_WINDOW = 96  # px: a shape larger than this is clipped to it


def _window_origin(lo: FloatArray) -> npt.NDArray[np.int64]:
    return np.floor(lo).astype(np.int64)


def _paint(img: RGB, origin: npt.NDArray[np.int64], mask: npt.NDArray[np.bool_],
           colour_of: npt.NDArray[np.uint8]) -> None:  # fmt: skip
    """Set the pixels ``mask`` marks in each shape's window (``origin`` + row/column) to
    ``colour_of`` (``(n, 3)`` per shape, or ``(n, k, k, 3)`` per pixel)."""
    car, row, col = np.nonzero(mask)
    x = origin[car, 0] + col
    y = origin[car, 1] + row
    h, w, _ = img.shape
    ok = (x >= 0) & (x < w) & (y >= 0) & (y < h)
    colours = colour_of[car] if colour_of.ndim == 2 else colour_of[car, row, col]
    img[y[ok], x[ok]] = colours[ok]


ANGLES = 72  # headings are drawn in steps of 5 degrees


class CarStamps:
    """Pixel masks of rotated car rectangles, made once per (size, heading step, border) and
    stamped into frames: a car costs two masked copies into a small slice of the frame."""

    def __init__(self) -> None:
        self._cache: dict[tuple[int, int, int, int], tuple[BoolMask, BoolMask, int]] = {}

    def _stamp(self, key: tuple[int, int, int, int]) -> tuple[BoolMask, BoolMask, int]:
        stamp = self._cache.get(key)
        if stamp is not None:
            return stamp
        hl, hw, border, a = key[0] / 4, key[1] / 4, key[2], key[3] * 2 * np.pi / ANGLES
        fx, fy = np.cos(a), -np.sin(a)  # pixel axes: y down
        size = int(np.ceil(2 * (hl + hw + border))) + 3
        half = size // 2
        d = np.arange(size) - half
        dx, dy = d[None, :], d[:, None]
        along, across = np.abs(dx * fx + dy * fy), np.abs(dy * fx - dx * fy)
        inner = (along <= hl) & (across <= hw)
        ring = (along <= hl + border) & (across <= hw + border) & ~inner
        stamp = self._cache[key] = (inner, ring, half)
        return stamp

    def draw(self, img: RGB, centre: FloatArray, heading: FloatArray, half: FloatArray,
             fill: RGB, outline: RGB, border: npt.NDArray[np.int64]) -> None:  # fmt: skip
        """Stamp cars: pixel ``centre`` (``(n, 2)``, x right, y down), ``heading`` (radians,
        counter-clockwise from +x on the map), half length/width (``(n, 2)`` px), ``fill`` and
        ``outline`` (``(n, 3)``), outline width ``border`` (px)."""
        h, w, _ = img.shape
        steps = np.rint(np.nan_to_num(heading) / (2 * np.pi) * ANGLES).astype(np.int64) % ANGLES
        q = np.rint(half * 4).astype(np.int64)
        cx, cy = np.rint(centre).astype(np.int64).T
        rows = zip(q[:, 0].tolist(), q[:, 1].tolist(), border.tolist(), steps.tolist(),
                   cx.tolist(), cy.tolist(), fill, outline, strict=True)  # fmt: skip
        for ql, qw, b, step, x, y, colour, edge in rows:
            inner, ring, k = self._stamp((ql, qw, b, step))
            x0, y0 = x - k, y - k
            size = inner.shape[0]
            if x0 >= 0 and y0 >= 0 and x0 + size <= w and y0 + size <= h:
                region = img[y0 : y0 + size, x0 : x0 + size]
            else:  # at the frame's edge: clip the stamp
                a0, b0 = max(0, -x0), max(0, -y0)
                a1, b1 = min(size, w - x0), min(size, h - y0)
                if a1 <= a0 or b1 <= b0:
                    continue
                region = img[y0 + b0 : y0 + b1, x0 + a0 : x0 + a1]
                inner, ring = inner[b0:b1, a0:a1], ring[b0:b1, a0:a1]
            region[ring] = edge
            region[inner] = colour


def fill_discs(img: RGB, centres: FloatArray, radius: float, colours: RGB) -> None:
    """Fill discs of ``radius`` px at ``centres`` (``(n, 2)`` pixels) with ``colours``."""
    if not len(centres):
        return
    size = int(min(MAX_WINDOW, 2 * np.ceil(radius) + 2))
    origin = _window_origin(centres - size / 2)
    offs = np.arange(size)
    dx = origin[:, 0, None, None] - centres[:, 0, None, None] + offs[None, None, :]
    dy = origin[:, 1, None, None] - centres[:, 1, None, None] + offs[None, :, None]
    _paint(img, origin, dx * dx + dy * dy <= radius * radius, colours)
