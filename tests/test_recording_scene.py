"""The ``/flowrun/scene`` topic (Foxglove's ``SceneUpdate``), decoded with third-party readers:
the ``mcap`` library reads the file, Foxglove's own protobuf classes and the schema embedded
in the log decode the messages."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.reader import make_reader
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.experiment.baseline import run_baseline
from flowrun.loading.loader import load_config
from flowrun.recording import open_log
from flowrun.recording.scene import SCENE_TOPIC, SCENE_TYPE
from flowrun.render import speed_colours, speed_top
from flowrun.render.colours import SIGNAL_COLOURS

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


def _scene_messages(path: Path) -> list[tuple[int, object, bytes]]:
    with open(path, "rb") as f:
        reader = make_reader(f)
        out = []
        for schema, channel, message in reader.iter_messages(topics=[SCENE_TOPIC]):
            assert schema is not None and schema.name == SCENE_TYPE
            assert schema.encoding == "protobuf" and channel.message_encoding == "protobuf"
            out.append((message.log_time, schema, message.data))
    return out


def _run(tmp: Path, name: str, steps: int, **kw: object) -> Path:
    cfg = load_config(CONFIGS / f"{name}.yaml", ["env.warmup_steps=0"])
    return run_baseline(cfg, steps=steps, out=tmp, **kw).logs[0]  # type: ignore[arg-type]


def _yaw(q: object) -> float:
    return float(2 * np.arctan2(q.z, q.w))  # type: ignore[attr-defined]


@pytest.mark.sumo
def test_scene_has_the_road_once_and_every_car_as_a_cube_where_the_log_puts_it(tmp_path):
    path = _run(tmp_path, "ring_wave", 30, scene=True)
    messages = _scene_messages(path)
    log = open_log(path)
    frames = {round(f.time * 1e9): f for f in log.frames()}
    assert len(messages) == len(frames) == 31
    # the schema in the log is enough to decode (as Foxglove does)
    fds = descriptor_pb2.FileDescriptorSet.FromString(messages[0][1].data)
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        pool.Add(fd)
    from_schema = message_factory.GetMessageClass(pool.FindMessageTypeByName(SCENE_TYPE))
    net_lanes = open_log(path).attachments["network.net.xml"].count(b"<lane ")
    for k, (stamp, _, data) in enumerate(messages):
        update = SceneUpdate.FromString(data)
        assert from_schema.FromString(data).SerializeToString() == update.SerializeToString()
        entities = {e.id: e for e in update.entities}
        assert ("road" in entities) == (k == 0)  # the road once
        if k == 0:
            road = entities["road"]
            assert len(road.lines) == net_lanes and road.frame_id == "map"
            assert all(ln.thickness > 3 and len(ln.points) >= 2 for ln in road.lines)
        cars = entities["cars"]
        frame = frames[stamp]
        assert cars.timestamp.seconds * 10**9 + cars.timestamp.nanos == stamp
        n = len(frame.ids)
        assert len(cars.cubes) == n + int(frame.is_rl.sum())  # AVs get a roof marker
        for i, cube in enumerate(cars.cubes[:n]):
            yaw = _yaw(cube.pose.orientation)
            front_x = cube.pose.position.x + np.cos(yaw) * cube.size.x / 2
            front_y = cube.pose.position.y + np.sin(yaw) * cube.size.x / 2
            assert front_x == pytest.approx(frame.x[i], abs=1e-6)
            assert front_y == pytest.approx(frame.y[i], abs=1e-6)
        if "legend" in entities:  # the scale grows with the fastest car; the legend says so
            text = entities["legend"].texts[0].text
            legend_top = float(text.split("green ")[1].split(" m/s")[0])
            assert legend_top == speed_top(max(frame.speed.max(), 0.0)) or k > 0
        want = speed_colours(frame.speed, legend_top) / 255
        got = np.array([(c.color.r, c.color.g, c.color.b) for c in cars.cubes[:n]])
        assert np.abs(got - want).max() < 0.003


@pytest.mark.sumo
def test_scene_lights_show_each_links_logged_state(tmp_path):
    path = _run(tmp_path, "grid0", 5, scene=True)
    signals = {round(s.time * 1e9): s for s in open_log(path).signals()}
    stamp, _, data = _scene_messages(path)[-1]
    lights = {e.id: e for e in SceneUpdate.FromString(data).entities}["lights"]
    assert lights.spheres
    colours = {SIGNAL_COLOURS[ch] for ch in "Gyr"}
    got = {(round(s.color.r * 255), round(s.color.g * 255), round(s.color.b * 255))
           for s in lights.spheres}  # fmt: skip
    assert got <= colours | {(140, 140, 140)}
    states = "".join(signals[stamp].states)
    assert sum(s.color.g > 0.6 and s.color.r < 0.1 for s in lights.spheres) == sum(
        ch in "Gg" for ch in states
    )


@pytest.mark.sumo
def test_scene_is_off_by_default_and_replay_foxglove_adds_it(tmp_path):
    path = _run(tmp_path, "ring_wave", 10)
    assert SCENE_TOPIC not in open_log(path).topics
    out = tmp_path / "scene.mcap"
    result = CliRunner().invoke(app, ["replay", str(path), "--foxglove", str(out)])
    assert result.exit_code == 0, result.output
    messages = _scene_messages(out)
    assert len(messages) == 11
    first = {e.id for e in SceneUpdate.FromString(messages[0][2]).entities}
    assert {"road", "cars", "legend"} <= first
