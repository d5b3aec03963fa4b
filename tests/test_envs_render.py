"""Rendering: a top-down RGB picture of the ring, and ``flowrun baseline --render`` GIFs."""

from __future__ import annotations

from pathlib import Path

import gymnasium
import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

import flowrun.envs  # noqa: F401 - registers flowrun/<Name>-v0
from flowrun.cli.main import app
from flowrun.envs.render import BACKGROUND, RL_OUTLINE, ring_layout, speed_colour

RING_WAVE = Path(__file__).resolve().parent.parent / "configs" / "ring_wave.yaml"


def test_speed_colour_goes_from_red_when_stopped_to_green_at_top_speed():
    r, g, b = speed_colour(0.0, 30.0)
    assert r > 200 and g < 60 and b < 60
    r, g, b = speed_colour(30.0, 30.0)
    assert g > 200 and r < 60
    assert speed_colour(-1.0, 30.0) == speed_colour(0.0, 30.0)
    assert speed_colour(99.0, 30.0) == speed_colour(30.0, 30.0)


def pixels_near(frame: np.ndarray, centre: np.ndarray, radius: float) -> np.ndarray:
    """The RGB values within ``radius`` pixels of ``centre`` (x right, y down)."""
    h, w, _ = frame.shape
    yy, xx = np.mgrid[0:h, 0:w]
    mask = (xx - centre[0]) ** 2 + (yy - centre[1]) ** 2 <= radius**2
    return frame[mask]


def count(pixels: np.ndarray, colour: tuple[int, int, int]) -> int:
    return int(np.all(pixels == np.array(colour), axis=1).sum())


@pytest.mark.sumo
def test_rgb_array_shows_stopped_cars_red_and_the_rl_car_outlined():
    env = gymnasium.make(
        "flowrun/WaveAttenuationPOEnv-v0", render_mode="rgb_array", warmup_steps=0, horizon=100
    )
    try:
        assert env.unwrapped.render() is None  # nothing to draw before reset
        env.reset(seed=0)
        frame = env.render()
        assert frame.dtype == np.uint8 and frame.shape == (400, 400, 3)
        inner = env.unwrapped
        layout = ring_layout(inner.k)
        ids = inner.k.vehicle.get_ids()
        rl = ids.index("rl_0")
        human = ids.index("idm_0")
        assert np.all(inner.k.vehicle.speed == 0)  # everyone stands at the start
        red = speed_colour(0.0, 30.0)
        for i in (rl, human):
            r, g, b = (int(c) for c in frame[tuple(np.round(layout.cars[i][::-1]).astype(int))])
            assert r > 180 and g < 80 and b < 80, (i, (r, g, b))
            assert count(pixels_near(frame, layout.cars[i], layout.car_radius), red) > 10
        outline = layout.car_radius + 1
        assert count(pixels_near(frame, layout.cars[rl], outline), RL_OUTLINE) > 10
        assert count(pixels_near(frame, layout.cars[human], outline), RL_OUTLINE) == 0
        assert tuple(frame[0, -1]) == BACKGROUND

        for _ in range(60):  # the humans drive off; the AV (action 0) stays where it is
            env.step(np.array([0.0], dtype=np.float32))
        frame = env.render()
        layout = ring_layout(inner.k)
        speeds = inner.k.vehicle.speed
        assert speeds.max() > 3.0
        for (x, y), v in zip(np.round(layout.cars).astype(int), speeds, strict=True):
            assert tuple(frame[y, x]) == speed_colour(float(v), 30.0)
    finally:
        env.close()


@pytest.mark.sumo
def test_baseline_render_writes_an_animated_gif(tmp_path):
    result = CliRunner().invoke(
        app,
        [
            "baseline",
            str(RING_WAVE),
            "--steps",
            "40",
            "--render",
            "--no-record",
            "--set",
            "env.warmup_steps=0",
            "--out",
            str(tmp_path),
        ],
    )
    assert result.exit_code == 0, result.output
    (gif,) = tmp_path.glob("ring_wave/*/render.gif")
    with Image.open(gif) as im:
        assert im.format == "GIF"
        assert im.n_frames > 1
        im.seek(0)
        first = np.asarray(im.convert("RGB")).copy()
        im.seek(im.n_frames - 1)
        last = np.asarray(im.convert("RGB"))
    assert not np.array_equal(first, last)  # the cars moved
