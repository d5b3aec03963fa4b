"""Rendering: the road from the network's lane shapes, cars at their map position coloured on
a scale that fits the run, AVs outlined, lights at their junctions; ``baseline --render``."""

from __future__ import annotations

import shutil
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

import flowrun.envs  # noqa: F401 - registers flowrun/<Name>-v0
from flowrun.cli.main import app
from flowrun.envs.factory import make_env
from flowrun.envs.render import kernel_road, render_kernel, snapshot
from flowrun.loading.loader import load_config
from flowrun.render import Painter, road_from_net_xml, speed_colours, speed_top
from flowrun.render.colours import AV_COLOUR, SIGNAL_COLOURS
from flowrun.render.picture import ROAD_COLOUR

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
RING_WAVE = CONFIGS / "ring_wave.yaml"

NET = b"""<net version="1.20">
  <edge id="a" from="n0" to="n1"><lane id="a_0" index="0" speed="10" length="100"
        shape="0,0 100,0"/></edge>
  <edge id="b" from="n1" to="n2"><lane id="b_0" index="0" speed="10" length="50"
        width="4" shape="100,0 100,50"/></edge>
  <edge id=":n1_0" function="internal"><lane id=":n1_0_0" index="0" speed="10" length="1"
        shape="100,0 100,1"/></edge>
  <junction id="n1" type="traffic_light" x="100" y="0" shape="98,-2 102,-2 102,2 98,2"/>
  <junction id=":n1_0_0" type="internal" x="100" y="0" shape="1,1 2,2 3,3"/>
  <connection from="a" to="b" fromLane="0" toLane="0" via=":n1_0_0" tl="n1" linkIndex="0"/>
  <connection from="a" to="b" fromLane="0" toLane="0" tl="n1" linkIndex="1"/>
</net>"""


def test_speed_scale_is_a_round_number_at_or_above_the_fastest_car():
    assert speed_top(8.5) == 10.0
    assert speed_top(23.0) == 25.0
    assert speed_top(0.0) == 1.0
    assert speed_top(30.0) == 30.0
    red, green = speed_colours([0.0, 10.0], 10.0).tolist()
    assert red[0] > 200 and red[1] < 60 and green[1] > 140 and green[0] < 60
    assert speed_colours([-1.0, 99.0], 10.0).tolist() == [red, green]  # clipped


def test_net_xml_gives_lanes_junction_outlines_and_one_signal_head_per_link():
    road = road_from_net_xml(NET)
    assert [lane.id for lane in road.lanes] == ["a_0", "b_0", ":n1_0_0"]
    assert road.lanes[1].width == 4.0 and road.lanes[0].width == 3.2
    assert len(road.junctions) == 1  # the internal junction has no outline drawn
    heads = sorted((h.link, round(h.x, 3), round(h.y, 3)) for h in road.signals)
    assert heads == [(0, 100.0, 0.8), (1, 100.0, -0.8)]  # lane end, spread across its width
    east, north = road.headings(
        ["a", "b"], np.array([0, 0]), np.array([50.0, 10.0]), np.zeros(2), np.zeros(2)
    )
    assert east == pytest.approx(0.0) and north == pytest.approx(np.pi / 2)


def _pixel(frame: np.ndarray, painter: Painter, x: float, y: float) -> tuple[int, ...]:
    px, py = painter.view.px(x, y)
    return tuple(int(c) for c in frame[round(float(py)), round(float(px))])


@pytest.mark.sumo
def test_rgb_array_draws_stopped_cars_red_where_they_are_and_outlines_the_av():
    env = gymnasium.make(
        "flowrun/WaveAttenuationPOEnv-v0", render_mode="rgb_array", warmup_steps=0, horizon=100
    )
    try:
        assert env.unwrapped.render() is None  # nothing to draw before reset
        env.reset(seed=0)
        frame = env.render()
        assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
        k = env.unwrapped.k
        shot = snapshot(k)
        painter = env.unwrapped._painter._painter
        road = kernel_road(k)
        heading = road.headings(shot.frame.edges, shot.frame.lanes, shot.frame.lane_pos,
                                shot.frame.x, shot.frame.y)  # fmt: skip
        red = tuple(speed_colours([0.0], 1.0)[0].tolist())
        for i, vid in enumerate(shot.frame.ids):
            # the car's middle: half a car length behind its front bumper
            mx = shot.frame.x[i] - 2.5 * np.cos(heading[i])
            my = shot.frame.y[i] - 2.5 * np.sin(heading[i])
            assert _pixel(frame, painter, mx, my) == red, vid
        rl = shot.frame.ids.index("rl_0")
        px, py = painter.view.px(shot.frame.x[rl], shot.frame.y[rl])
        near = frame[int(py) - 8 : int(py) + 8, int(px) - 8 : int(px) + 8].reshape(-1, 3)
        assert (near == AV_COLOUR).all(axis=1).sum() > 5
        for _ in range(60):  # the humans drive off
            env.step(np.array([0.0], dtype=np.float32))
        assert not np.array_equal(env.render(), frame)
        assert env.unwrapped._painter.fastest > 3.0  # the scale follows the fastest car
    finally:
        env.close()


@pytest.mark.sumo
def test_merge_picture_shows_the_on_ramp_and_figure_eight_its_crossing():
    for name in ("merge", "figure_eight"):
        env = make_env(load_config(CONFIGS / f"{name}.yaml"), render_mode="rgb_array")
        try:
            env.reset(seed=0)
            k = env.k
            frame = render_kernel(k, top=10.0)
            road = kernel_road(k)
            painter = Painter(road, 10.0, lengths={})
            assert frame.shape == (painter.view.height, painter.view.width, 3)
            drawn = 0
            lanes = [lane for lane in road.lanes if not lane.internal]
            for lane in lanes:  # every lane's middle is road (or a car on it)
                mid = lane.shape[len(lane.shape) // 2]
                if _pixel(frame, painter, *mid) == ROAD_COLOUR:
                    drawn += 1
            assert drawn >= 0.8 * len(lanes), (name, drawn, len(lanes))
            # not a circle: the lanes' points are far from one common radius
            pts = np.concatenate([lane.shape for lane in road.lanes])
            r = np.hypot(*(pts - pts.mean(axis=0)).T)
            assert r.std() > 0.2 * r.mean()
        finally:
            env.close()


@pytest.mark.sumo
def test_grid_picture_shows_each_light_state_at_its_junction():
    env = make_env(load_config(CONFIGS / "grid0.yaml"), render_mode="rgb_array")
    try:
        env.reset(seed=0)
        k = env.k
        frame = render_kernel(k, top=10.0)
        road = kernel_road(k)
        painter = Painter(road, 10.0)
        states = dict(zip(k.traffic_light.get_ids(), k.traffic_light.states, strict=True))
        assert road.signals
        hits = sum(
            _pixel(frame, painter, h.x, h.y) == SIGNAL_COLOURS[states[h.light][h.link]]
            for h in road.signals
            if states[h.light][h.link] in SIGNAL_COLOURS
        )
        assert hits >= 0.8 * len(road.signals)
    finally:
        env.close()


@pytest.mark.sumo
def test_baseline_render_writes_an_animation_from_the_start_on_one_scale(tmp_path):
    result = CliRunner().invoke(
        app,
        ["baseline", str(RING_WAVE), "--steps", "40", "--render", "--no-record",
         "--set", "env.warmup_steps=0", "--out", str(tmp_path)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    (gif,) = tmp_path.glob("ring_wave/*/render.gif")
    with Image.open(gif) as im:
        assert im.format == "GIF"
        assert im.n_frames == 5  # t = 0, 1, 2, 3, 4 s
        im.seek(0)
        first = np.asarray(im.convert("RGB")).copy()
        im.seek(im.n_frames - 1)
        last = np.asarray(im.convert("RGB"))
    assert not np.array_equal(first, last)  # the cars moved
    mp4 = gif.with_suffix(".mp4")
    if shutil.which("ffmpeg") is None:
        assert "no MP4: ffmpeg is not installed" in result.output
        assert not mp4.exists()
    else:
        assert mp4.stat().st_size > 0
