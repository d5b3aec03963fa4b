"""Raster frames of the traffic on its road (PIL, no display): the road drawn once, the cars as
oriented rectangles at their map position coloured by speed, AVs outlined, signal heads in
their light's colour, and the time and headline numbers in the header with the colour legend.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt
from PIL import Image, ImageDraw, ImageFont

from flowrun.render.colours import AV_COLOUR, SIGNAL_OFF, signal_colour, speed_colours
from flowrun.render.raster import RGB, CarStamps, fill_discs
from flowrun.render.road import Road
from flowrun.types import BoolArray, FloatArray, IntArray

BACKGROUND = (250, 250, 247)
ROAD_COLOUR = (120, 120, 120)
JUNCTION_COLOUR = (135, 135, 135)
HEADER = 44  # px of the header band (caption and legend)
MARGIN = 12  # px around the road
CAR_LENGTH = 5.0  # m, when a type's length is not known
CAR_WIDTH = 1.8  # m
CAR_OUTLINE = (40, 40, 40)
_AV, _OUTLINE = np.array(AV_COLOUR, np.uint8), np.array(CAR_OUTLINE, np.uint8)


class FrameLike(Protocol):
    """What a picture needs of one instant (a :class:`~flowrun.recording.VehicleFrame` fits)."""

    time: float
    ids: list[str]
    types: list[str]
    edges: list[str]
    lanes: IntArray
    lane_pos: FloatArray
    x: FloatArray
    y: FloatArray
    speed: FloatArray
    is_rl: BoolArray


@dataclass(frozen=True)
class View:
    """World (m, y up) to pixel (x right, y down) mapping of a picture ``width`` x ``height``."""

    xmin: float
    ymax: float
    scale: float  # px per m
    width: int
    height: int

    @classmethod
    def fit(cls, bounds: tuple[float, float, float, float], size: int = 720) -> View:
        """The view that fits ``bounds`` into at most ``size`` px on its longer side (up to
        twice that for a road much longer than wide; the shorter side at least 160 px, both
        even so that video encoders take them)."""
        xmin, ymin, xmax, ymax = bounds
        w, h = max(xmax - xmin, 1.0), max(ymax - ymin, 1.0)
        if w > 2.5 * h:  # a long straight road (merge, bottleneck): a wider picture
            size = min(2 * size, round(size * w / h / 2.5))
        inner = size - 2 * MARGIN
        scale = inner / max(w, h)
        width = max(math.ceil(w * scale) + 2 * MARGIN, 360)
        height = max(math.ceil(h * scale) + 2 * MARGIN, 160) + HEADER
        xmin -= (width - 2 * MARGIN - w * scale) / 2 / scale
        ymax += (height - HEADER - 2 * MARGIN - h * scale) / 2 / scale
        return cls(xmin, ymax, scale, width + width % 2, height + height % 2)

    def px(self, x: npt.ArrayLike, y: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Pixel coordinates of map points."""
        px = (np.asarray(x, dtype=np.float64) - self.xmin) * self.scale + MARGIN
        py = (self.ymax - np.asarray(y, dtype=np.float64)) * self.scale + MARGIN + HEADER
        return px, py


def car_rects(
    view: View, x: FloatArray, y: FloatArray, heading: FloatArray, length: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Pixel centre and half length/width (``(n, 2)`` each) of cars
    whose front bumper is at ``x``, ``y`` (m), pointing along ``heading`` (radians); at least
    5 x 3 px so that a car stays visible."""
    px, py = view.px(x, y)
    ln = np.maximum(length * view.scale, 5.0)
    wd = max(CAR_WIDTH * view.scale, 3.0)
    h = np.nan_to_num(heading)
    forward = np.stack([np.cos(h), -np.sin(h)], axis=1)  # pixel axes: y down
    centre = np.stack([px, py], axis=1) - forward * (ln / 2)[:, None]
    half = np.stack([ln / 2, np.full(len(ln), wd / 2)], axis=1)
    return centre, half


class Painter:
    """Draws frames of one run: the road and legend are drawn once, each frame only adds cars,
    signals and the caption.

    Args:
        road: the road (``None``: the log has no geometry; the header says so).
        top: top of the speed scale, m/s (:func:`~flowrun.render.colours.speed_top`).
        bounds: map area to show (default: the road's).
        size: longest side of the road area, px.
        lengths: car length per vehicle type, m (default 5 m).
    """

    def __init__(
        self,
        road: Road | None,
        top: float,
        bounds: tuple[float, float, float, float] | None = None,
        size: int = 720,
        lengths: Mapping[str, float] | None = None,
    ) -> None:
        self.road = road
        self.top = top
        if bounds is None:
            bounds = road.bounds if road is not None else (-50.0, -50.0, 50.0, 50.0)
        self.view = View.fit(bounds, size)
        self.lengths = dict(lengths or {})
        self.font = ImageFont.load_default(size=13)
        self.small = ImageFont.load_default(size=11)
        self.fast = ImageFont.load_default_imagefont()  # a bitmap font: the per-frame text
        self._stamps = CarStamps()
        background = self._background()
        self._body = np.asarray(background, dtype=np.uint8).copy()
        self._header = background.crop((0, 0, self.view.width, HEADER))
        heads = self.road.signals if self.road is not None else []
        hx, hy = self.view.px([h.x for h in heads], [h.y for h in heads])
        self._heads = np.stack([hx, hy], axis=1).reshape(-1, 2)

    def _background(self) -> Image.Image:
        v = self.view
        img = Image.new("RGB", (v.width, v.height), BACKGROUND)
        draw = ImageDraw.Draw(img)
        road = self.road
        if road is not None:
            for shape in road.junctions:
                px, py = v.px(shape[:, 0], shape[:, 1])
                draw.polygon(list(zip(px.tolist(), py.tolist(), strict=True)), fill=JUNCTION_COLOUR)
            for lane in sorted(road.lanes, key=lambda la: la.internal):
                px, py = v.px(lane.shape[:, 0], lane.shape[:, 1])
                width = max(1, round(lane.width * v.scale))
                pts = list(zip(px.tolist(), py.tolist(), strict=True))
                draw.line(pts, fill=ROAD_COLOUR, width=width, joint="curve")
        draw.rectangle([0, 0, v.width, HEADER - 1], fill=(255, 255, 255))
        draw.line([(0, HEADER - 1), (v.width, HEADER - 1)], fill=(200, 200, 200))
        self._legend(draw)
        if road is None:
            draw.text(
                (8, HEADER + 4),
                "no road geometry in this log: cars only",
                fill=(160, 0, 0),
                font=self.small,
            )
        return img

    def _legend(self, draw: ImageDraw.ImageDraw) -> None:
        v = self.view
        bar_w = 120
        x0 = v.width - bar_w - 70
        y0 = 8
        steps = np.linspace(0.0, self.top, bar_w)
        for i, rgb in enumerate(speed_colours(steps, self.top).tolist()):
            draw.line([(x0 + i, y0), (x0 + i, y0 + 10)], fill=tuple(rgb))
        draw.text((x0, y0 + 13), "0", fill=(0, 0, 0), font=self.small)
        label = f"{self.top:g} m/s"
        draw.text((x0 + bar_w, y0 + 13), label, fill=(0, 0, 0), font=self.small, anchor="ma")
        ax = x0 + bar_w + 36
        draw.rectangle([ax, y0, ax + 14, y0 + 9], outline=AV_COLOUR, width=2)
        draw.text((ax, y0 + 13), "AV", fill=AV_COLOUR, font=self.small)

    def draw(
        self,
        frame: FrameLike,
        signals: tuple[Sequence[str], Sequence[str]] | None = None,
        caption: str | None = None,
    ) -> RGB:
        """One RGB frame ``(height, width, 3)``.

        Args:
            frame: the cars at one instant.
            signals: traffic lights' ``(ids, state strings)`` at that instant.
            caption: text after the time (default: car count and mean speed).
        """
        out = self._body.copy()
        if signals is not None and self.road is not None and self.road.signals:
            self._signals(out, signals)
        self._cars(out, frame)
        speed = np.asarray(frame.speed, dtype=np.float64)
        if caption is None:
            mean = f"{float(speed.mean()):.2f} m/s" if speed.size else "-"
            caption = f"{speed.size} cars   mean speed {mean}"
        header = self._header.copy()
        draw = ImageDraw.Draw(header)
        draw.text((8, 8), f"t = {frame.time:.1f} s", fill=(0, 0, 0), font=self.fast)
        draw.text((8, 26), caption, fill=(60, 60, 60), font=self.fast)
        out[:HEADER] = np.asarray(header)
        return out

    def _signals(self, out: RGB, signals: tuple[Sequence[str], Sequence[str]]) -> None:
        assert self.road is not None
        states = dict(zip(signals[0], signals[1], strict=False))
        colours = []
        for head in self.road.signals:
            state = states.get(head.light, "")
            colours.append(
                signal_colour(state[head.link]) if head.link < len(state) else SIGNAL_OFF
            )
        r = max(2.5, 0.9 * self.view.scale)
        fill_discs(out, self._heads, r, np.array(colours, dtype=np.uint8))

    def _cars(self, out: RGB, frame: FrameLike) -> None:
        n = len(frame.ids)
        if not n:
            return
        x = np.asarray(frame.x, dtype=np.float64)
        y = np.asarray(frame.y, dtype=np.float64)
        if self.road is not None and len(frame.edges) == n:
            heading = self.road.headings(frame.edges, np.asarray(frame.lanes), frame.lane_pos, x, y)
        else:
            heading = np.zeros(n)
        lengths = np.array([self.lengths.get(t, CAR_LENGTH) for t in frame.types]) if self.lengths \
            else np.full(n, CAR_LENGTH)  # fmt: skip
        centre, half = car_rects(self.view, x, y, heading, lengths)
        rl = np.asarray(frame.is_rl, dtype=bool)
        outline = np.where(rl[:, None], _AV, _OUTLINE).astype(np.uint8)
        fills = speed_colours(frame.speed, self.top)
        self._stamps.draw(out, centre, heading, half, fills, outline, np.where(rl, 2, 1))
