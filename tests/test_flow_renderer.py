"""Flow's ``PygletRenderer`` (``flowrun.renderer.pyglet_renderer``): frames drawn headless with
Flow's geometry and colours, the agent's sight, saving, and its errors (no SUMO)."""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np
import pytest

from flowrun.renderer.pyglet_renderer import PygletRenderer

#: one lane, a 100 m x 60 m rectangle
LANE = [0.0, 0.0, 100.0, 0.0, 100.0, 60.0, 0.0, 60.0, 0.0, 0.0]
HUMAN = [[50.0, 0.0, 90.0]]  # on the bottom side heading east (SUMO angle, degrees)
AV = [[100.0, 30.0, 0.0]]  # on the right side heading north


def frame(mode: str, **kw: object) -> tuple[PygletRenderer, np.ndarray]:
    r = PygletRenderer([LANE], mode, sight_radius=10, pxpm=2, **kw)  # type: ignore[arg-type]
    return r, r.render(HUMAN, AV, [0.5], [1.0], [[0, 0.1, "h"]], [[0, 0.1, "a"]])


def behind(r: PygletRenderer, x: float, y: float, dx: float, dy: float) -> tuple[int, int]:
    """The pixel (row, col) 2 m behind map point (x, y) against heading (dx, dy)."""
    ((px, py),) = r._px(np.array([x - 2 * dx, y - 2 * dy]))
    return int(py), int(px)


def test_frame_size_and_car_colours_follow_flows_rgb_mode() -> None:
    r, img = frame("rgb")
    # Flow's size: (int extent + 2 * sight radius) * pxpm per axis
    assert img.shape == ((60 + 20) * 2, (100 + 20) * 2, 3) and img.dtype == np.uint8
    assert tuple(img[behind(r, 50, 0, 1, 0)]) == (0, 225, 0)  # a human: green
    assert tuple(img[behind(r, 100, 30, 0, 1)]) == (0, 150, 200)  # an AV: blue
    assert tuple(img[5, 5]) == (32, 32, 32)  # background, outside the road
    # the car's triangle points along its heading: nothing drawn just ahead of the human
    ((px, py),) = r._px(np.array([53.0, 2.0]))
    assert tuple(img[int(py), int(px)]) == (32, 32, 32)


def test_dynamic_and_gray_modes() -> None:
    r, img = frame("drgb")
    slow = tuple(img[behind(r, 50, 0, 1, 0)])
    r2 = PygletRenderer([LANE], "drgb", sight_radius=10, pxpm=2)
    fast = tuple(r2.render(HUMAN, AV, [1.0], [1.0], [], [])[behind(r, 50, 0, 1, 0)])
    assert slow != fast and fast[1] < slow[1]  # a darker green for a higher value
    for mode in ("gray", "dgray"):
        r, img = frame(mode)
        assert img.shape == (160, 240)  # one channel
    assert frame("gray")[1][behind(r, 50, 0, 1, 0)] == 100


def test_sight_is_the_circle_around_the_car() -> None:
    r, _ = frame("rgb", show_radius=True)
    sight = r.get_sight(AV[0], "a")
    assert sight.shape == (40, 40, 3)  # 2 * sight_radius * pxpm
    assert sight[0, 0].tolist() == [0, 0, 0]  # outside the circle: blacked out
    assert sight[23, 20].tolist() == [0, 150, 200]  # the AV, 2 m behind its tip (centre)
    assert not (sight[:, :, 1] == 225).any()  # the human, 58 m away, is out of sight



def test_saved_data_round_trips_and_a_closed_renderer_refuses(tmp_path: Path) -> None:
    r = PygletRenderer([LANE], "drgb", save_render=True, path=str(tmp_path), sight_radius=10)
    step = [HUMAN, AV, [0.5], [1.0], [[0, 0.1, "h"]], [[0, 0.1, "a"]]]
    r.render(*step)
    saved = np.load(r.close(), allow_pickle=True)
    assert saved[0] == [LANE] and saved[1] == step
    assert list(Path(r.path).glob("frame_000001.png"))
    with pytest.raises(ctypes.ArgumentError, match="closed"):  # Flow's error type
        r.render(*step)
    assert PygletRenderer([LANE], "rgb").close() == ""
    with pytest.raises(ValueError, match="'hd'"):
        PygletRenderer([LANE], "hd")
