"""Pictures of a running simulation on its own road (``rgb_array``, ``baseline --render``).

:func:`render_kernel` is the one call "draw this env state as an RGB array"; :class:`EnvPainter`
keeps the road (read once from the network file) and a speed scale that only grows within an
episode, so an ``rgb_array`` stream keeps its colours meaning the same.
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import numpy as np
import numpy.typing as npt

from flowrun.envs.frames import snapshot_frame, snapshot_signals
from flowrun.kernel import Kernel
from flowrun.render import Painter, Road, Snapshot, ring_road, road_from_net_xml, speed_top

RGB = npt.NDArray[np.uint8]


@lru_cache(maxsize=8)
def _road_of_file(path: str, mtime_ns: int) -> Road:
    return road_from_net_xml(Path(path).read_bytes())


def kernel_road(k: Kernel) -> Road:
    """The road of the kernel's network: its ``.net.xml`` lane shapes (a circle of the
    network's length when there is no network file)."""
    net = k.net_file
    if net is not None and net.is_file():
        return _road_of_file(str(net), net.stat().st_mtime_ns)
    spec = k.network.spec
    return ring_road(float(spec.length), max((e.lanes for e in spec.edges), default=1))


def _map_xy(k: Kernel) -> tuple[np.ndarray, np.ndarray]:
    """Every car's map position, m, also where the kernel does not read it every step."""
    vk = k.vehicle
    if vk.read_xy:
        return vk.x, vk.y
    if vk.lane_table is None:  # a closed ring: positions map onto its lane shapes
        return vk.placement().xy(np.asarray(vk.position), np.asarray(vk.lanes))
    pts = np.array([vk.get_2d_position(v) for v in vk.get_ids()], dtype=np.float64)
    pts = pts.reshape(-1, 2)
    return pts[:, 0], pts[:, 1]


def snapshot(k: Kernel) -> Snapshot:
    """The cars (and lights) of the kernel's current step, to draw now or later."""
    signals = snapshot_signals(k, 0)
    x, y = _map_xy(k)
    frame = replace(snapshot_frame(k, 0), x=x, y=y)
    return Snapshot(frame, None if signals is None else (signals.ids, signals.states))


def vehicle_lengths(k: Kernel) -> dict[str, float]:
    """Length of each vehicle group's cars, m (what the pictures draw)."""
    lengths = {}
    for cls in k.vehicle.table.classes:
        length = getattr(cls, "length", None)
        if isinstance(length, int | float) and length > 0:
            lengths[str(cls.name)] = float(length)
    return lengths


def render_kernel(k: Kernel, top: float | None = None, size: int = 720) -> RGB:
    """The simulation's current state as an RGB array ``(height, width, 3)``: the road from the
    network's lane shapes, cars coloured by speed from 0 to ``top`` m/s (default: a round
    number at or above the fastest car now), AVs outlined, signal states at their junctions."""
    shot = snapshot(k)
    speed = np.asarray(shot.frame.speed)
    if top is None:
        top = speed_top(float(speed.max()) if speed.size else 0.0)
    return Painter(kernel_road(k), top, size=size, lengths=vehicle_lengths(k)).draw(
        shot.frame, shot.signals
    )


class EnvPainter:
    """The ``rgb_array`` renderer of one env: the painter is rebuilt only when the network
    file or the speed scale changes; the scale is the fastest speed seen this episode,
    rounded up (:func:`~flowrun.render.speed_top`)."""

    def __init__(self, size: int = 720) -> None:
        self.size = size
        self.fastest = 0.0
        self._key: tuple[object, float] | None = None
        self._painter: Painter | None = None

    def reset(self) -> None:
        """Start a new episode's scale."""
        self.fastest = 0.0

    def __call__(self, k: Kernel) -> RGB:
        shot = snapshot(k)
        speed = np.asarray(shot.frame.speed)
        if speed.size:
            self.fastest = max(self.fastest, float(speed.max()))
        top = speed_top(self.fastest)
        road = kernel_road(k)
        key = (id(road), top)
        if self._painter is None or key != self._key:
            self._painter = Painter(road, top, size=self.size, lengths=vehicle_lengths(k))
            self._key = key
        return self._painter.draw(shot.frame, shot.signals)
