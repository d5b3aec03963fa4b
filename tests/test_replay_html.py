"""``flowrun replay LOG --html OUT``: one self-contained page; checked in a real browser
(headless Chromium: load, seek, screenshot, cars where the log puts them)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.experiment.baseline import run_baseline
from flowrun.loading.loader import load_config
from flowrun.recording import McapRecorder, open_log
from flowrun.render import ring_road, speed_colours
from flowrun.replay import html as html_mod
from flowrun.replay.html import player_data, write_html

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
SIDE, BAR, PAD = 280, 40, 16  # the page's side panel, tool bar and fit margin, px
WIDTH, HEIGHT = 1000, 700


@pytest.fixture(scope="module")
def ring_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("runs")
    cfg = load_config(CONFIGS / "ring_wave.yaml", ["env.warmup_steps=0"])
    result = run_baseline(cfg, steps=150, out=out)
    return result.logs[0]


def _page_data(page: Path) -> dict:
    text = page.read_text(encoding="utf-8")
    match = re.search(r"const D = (\{.*?\});\n", text, re.S)
    assert match is not None
    return json.loads(match.group(1).replace("<\\/", "</"))


@pytest.mark.sumo
def test_page_is_one_file_with_the_road_every_step_and_no_network_access(ring_log, tmp_path):
    page = tmp_path / "ring.html"
    report = write_html(open_log(ring_log), page)
    assert report.stride == 1 and report.frames == 151 and report.notes == []
    text = page.read_text(encoding="utf-8")
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", text)  # nothing to fetch
    assert "fetch(" not in text and "XMLHttpRequest" not in text
    data = _page_data(page)
    assert data["road"]["lanes"] and len(data["times"]) == 151
    assert data["vehicles"]["rl"].count(1) == 1 and data["headline"]["collisions"] == "0"
    assert data["top"] >= max(s.max_speed for s in open_log(ring_log).stats())


@pytest.mark.sumo
def test_html_refuses_an_existing_file_a_folder_and_an_unwritable_place(ring_log, tmp_path):
    runner = CliRunner()
    existing = tmp_path / "taken.html"
    existing.write_text("mine")
    not_a_dir = tmp_path / "file"
    not_a_dir.write_text("x")
    for target, says in (
        (existing, "exists"),
        (tmp_path, "is a folder"),
        (not_a_dir / "page.html", "cannot write"),
    ):
        result = runner.invoke(app, ["replay", str(ring_log), "--html", str(target)])
        assert result.exit_code == 1, result.output
        assert says in result.output
        assert "Traceback" not in result.output
    assert existing.read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "taken.html"]  # no partial
    result = runner.invoke(app, ["replay", str(ring_log), "--html", str(tmp_path / "ok.html")])
    assert result.exit_code == 0 and "wrote" in result.output


@pytest.mark.sumo
def test_a_log_without_geometry_plays_its_cars_and_says_what_it_cannot_draw(ring_log, tmp_path):
    log = open_log(ring_log)
    bare = tmp_path / "bare.mcap"
    stats = {s.step: s for s in log.stats()}
    with McapRecorder(bare, metadata=log.metadata, attachments={}) as rec:
        for frame in log.frames():
            rec.write(frame, stats[frame.step])
    data, _ = player_data(open_log(bare))
    assert data["road"] is None
    assert any("road is not drawn" in n and "network.net.xml" in n for n in data["notes"])
    assert len(data["times"]) == 151  # the cars are all there


@pytest.mark.sumo
def test_big_runs_are_thinned_and_the_page_says_so(ring_log, monkeypatch):
    monkeypatch.setattr(html_mod, "BUDGET_BYTES", 151 * 22 * 12 // 4)
    data, stride = player_data(open_log(ring_log))
    assert stride == 4 and len(data["times"]) == 38
    assert any("every 4th logged step" in n for n in data["notes"])


def test_numpy_ring_road_is_a_circle_of_the_logged_length():
    road = ring_road(230.0)
    r = np.hypot(*road.lanes[0].shape.T)
    assert np.allclose(r, 230.0 / (2 * np.pi) + 1.6)


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def _screenshot(page: Path, fragment: str, out: Path, tmp: Path) -> np.ndarray:
    browser = _chromium()
    assert browser is not None
    profile = Path(tempfile.mkdtemp(dir=tmp))
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", f"--user-data-dir={profile}", "--hide-scrollbars",
           "--force-device-scale-factor=1", f"--window-size={WIDTH},{HEIGHT}",
           f"--screenshot={out}", f"{page.as_uri()}#{fragment}"]  # fmt: skip
    subprocess.run(cmd, capture_output=True, timeout=120, check=False)
    assert out.is_file(), "chromium wrote no screenshot"
    with Image.open(out) as im:
        return np.asarray(im.convert("RGB"))


@pytest.mark.sumo
@pytest.mark.skipif(_chromium() is None, reason="chromium is not installed (.ci/run installs it)")
def test_browser_draws_each_car_where_the_log_puts_it(ring_log, tmp_path):
    page = tmp_path / "ring.html"
    write_html(open_log(ring_log), page)
    data = _page_data(page)
    seek = 10.0
    frame = next(f for f in open_log(ring_log).frames() if abs(f.time - seek) < 1e-6)
    shot = _screenshot(page, f"t={seek}", tmp_path / "shot.png", tmp_path)
    assert shot.shape[:2] == (HEIGHT, WIDTH)
    # the page's fit: the road's bounds centred in the canvas left of the side panel
    x0, y0, x1, y1 = data["bounds"]
    cw, ch = WIDTH - SIDE, HEIGHT - BAR
    s = min((cw - 2 * PAD) / (x1 - x0), (ch - 2 * PAD) / (y1 - y0))
    ox, oy = (cw - (x1 - x0) * s) / 2 - x0 * s, (ch + (y1 - y0) * s) / 2 + y0 * s
    q = data["quant"]
    top = data["top"]
    hits = 0
    for i in range(len(frame.ids)):
        x = q["x0"] + round((frame.x[i] - q["x0"]) / q["q"]) * q["q"]
        y = q["y0"] + round((frame.y[i] - q["y0"]) / q["q"]) * q["q"]
        # heading: the ring's tangent at the car (the page takes it from the lane shape)
        ang = np.arctan2(y - (y0 + y1) / 2, x - (x0 + x1) / 2) + np.pi / 2
        lpx = max(5.0 * s, 5.0)
        px = ox + x * s - np.cos(ang) * lpx / 2
        py = BAR + oy - y * s + np.sin(ang) * lpx / 2
        want = speed_colours([round(frame.speed[i] / (top / 250)) * top / 250], top)[0]
        got = shot[round(py), round(px)].astype(int)
        if np.abs(got - want.astype(int)).max() <= 3:
            hits += 1
    assert hits >= len(frame.ids) - 1, (hits, len(frame.ids))
    # and not at t = 0: the cars moved, so the picture differs from the start
    start = _screenshot(page, "t=0", tmp_path / "start.png", tmp_path)
    assert not np.array_equal(start[BAR:, : WIDTH - SIDE], shot[BAR:, : WIDTH - SIDE])


def test_numpy_backend_log_plays_on_a_circle_of_its_length(tmp_path):
    from flowrun.fastring.record import record_episode

    cfg = load_config(CONFIGS / "ring_wave_numpy.yaml", ["env.horizon=20", "env.warmup_steps=0"])
    path = tmp_path / "numpy.mcap"
    record_episode(cfg, path, seed=0)
    log = open_log(path)
    data, _ = player_data(log)
    assert data["notes"] == [] and len(data["road"]["lanes"]) == 1
    pts = np.array(data["road"]["lanes"][0][2]).reshape(-1, 2)
    length = float(log.metadata["network_length"])
    assert np.hypot(*pts.T) == pytest.approx(length / (2 * np.pi) + 1.6, abs=0.01)
    frame = next(log.frames())  # the cars sit on that circle
    assert np.hypot(frame.x, frame.y) == pytest.approx(length / (2 * np.pi) + 1.6, abs=1e-6)


@pytest.mark.sumo
def test_a_time_window_and_vehicles_select_what_the_page_plays(ring_log):
    chosen = next(open_log(ring_log).frames()).ids[:2]
    data, _ = player_data(open_log(ring_log), 5.0, 10.0, chosen)
    assert data["times"][0] == pytest.approx(5.0) and data["times"][-1] == pytest.approx(10.0)
    assert sorted(data["vehicles"]["ids"]) == sorted(chosen)


@pytest.mark.sumo
@pytest.mark.skipif(_chromium() is None, reason="chromium is not installed (.ci/run installs it)")
def test_browser_shows_the_chosen_cars_id_speed_leader_and_headway(ring_log, tmp_path):
    page = tmp_path / "ring.html"
    write_html(open_log(ring_log), page)
    frame = next(f for f in open_log(ring_log).frames() if abs(f.time - 10.0) < 1e-6)
    i = 3
    vid = frame.ids[i]
    profile = Path(tempfile.mkdtemp(dir=tmp_path))
    cmd = [_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", f"--user-data-dir={profile}", f"--window-size={WIDTH},{HEIGHT}",
           "--dump-dom", f"{page.as_uri()}#t=10&car={vid}"]  # fmt: skip
    dom = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False).stdout
    panel = re.search(r'<div id="car">(.*?)</div>', dom, re.S)
    assert panel is not None, dom[:500]
    cells = dict(re.findall(r"<td>(.*?)</td><td>(.*?)</td>", panel.group(1)))
    top = _page_data(page)["top"]
    assert cells["id"] == vid
    assert float(cells["speed"].split()[0]) == pytest.approx(frame.speed[i], abs=top / 250)
    assert cells["leader"] == (frame.leader[i] or "none")
    assert float(cells["headway"].split()[0]) == pytest.approx(frame.headway[i], abs=0.06)
