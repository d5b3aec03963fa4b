"""``/flowrun/traffic_lights``: what the lights showed, logged per step, read back and replayed.

Real SUMO, seeded: grid0 (3 x 3 lights) for a few hundred steps under max-pressure (which sets
the lights every step) and fixed-time, run by ``Experiment`` as ``flowrun baseline`` does,
into a full log and a thinned one at once.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from flowrun.cli.commands_replay import register
from flowrun.envs.base import Env
from flowrun.envs.factory import make_env
from flowrun.experiment import Experiment
from flowrun.experiment.baseline import open_run_log
from flowrun.experiment.signal_baselines import SignalRun
from flowrun.recording import McapRecorder, SignalFrame, open_log
from flowrun.recording.schema import SignalFrameMsg
from flowrun.recording.signals import SignalEncoder, decode_signals
from flowrun.replay import summarize
from flowrun.replay.signals import (
    GREEN,
    RED,
    UNKNOWN,
    YELLOW,
    approach_colour,
    intersection_rows,
    signal_series,
)
from tests.conftest import load

STEPS = 300
THIN = 5


class Watch(SignalRun):
    """The signal baseline's hooks, also keeping what ``k.traffic_light`` reported per step."""

    def __init__(self, env: Env, controller: str) -> None:
        super().__init__(load("grid0", f"traffic_lights.controller={controller}").traffic_lights)
        self.seen: dict[int, tuple[list[str], list[str], list[int], list[str]]] = {}

    def _keep(self, env: Env) -> None:
        tk = env.k.traffic_light
        self.seen[env.k.simulation.step_count] = (
            tk.get_ids(), [tk.get_state(t) for t in tk.get_ids()],
            [tk.get_phase(t) for t in tk.get_ids()], [tk.get_program(t) for t in tk.get_ids()],
        )  # fmt: skip

    def on_reset(self, env: Env) -> None:
        self._keep(env)  # the frame of the reset is taken before any controller acts
        super().on_reset(env)

    def after_step(self, env: Env) -> None:
        super().after_step(env)
        self._keep(env)


class Tee:
    """A frame sink writing to several recorders."""

    def __init__(self, *sinks: Any) -> None:
        self.sinks = sinks

    def write(self, *args: Any) -> None:
        for sink in self.sinks:
            sink.write(*args)

    def close(self) -> None:
        for sink in self.sinks:
            sink.close()


def _run(tmp: Path, controller: str, seed: int = 0) -> dict[str, Any]:
    cfg = load("grid0", f"traffic_lights.controller={controller}", f"env.horizon={STEPS}")
    env = make_env(cfg, work_dir=tmp / "sumo")
    watch = Watch(env, controller)

    def sink(run: int) -> Tee:
        full = open_run_log(tmp / "full.mcap", env, cfg, seed, run)
        thin = open_run_log(tmp / "thin.mcap", env, cfg, seed, run, record_every=THIN)
        return Tee(full, thin)

    try:
        Experiment(env, sink_factory=sink, hooks=watch).run(1, STEPS, seed=seed)
    finally:
        env.close()
    return {"full": tmp / "full.mcap", "thin": tmp / "thin.mcap", "seen": watch.seen,
            "metrics": watch.results[0]}  # fmt: skip


@pytest.fixture(scope="module")
def max_pressure(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return _run(tmp_path_factory.mktemp("max_pressure"), "max_pressure")


@pytest.fixture(scope="module")
def fixed_time(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return _run(tmp_path_factory.mktemp("fixed_time"), "fixed_time")


@pytest.fixture(scope="module")
def old_log(max_pressure: dict[str, Any], tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The same run as logged before the lights were: vehicles and stats only."""
    log = open_log(max_pressure["full"])
    out = tmp_path_factory.mktemp("old") / "old.mcap"
    stats = {s.step: s for s in log.stats()}
    with McapRecorder(out, metadata=log.metadata, attachments=log.attachments) as rec:
        for frame in log.frames():
            rec.write(frame, stats[frame.step])
    return out


def _cli(*args: object) -> Any:
    app = typer.Typer()

    @app.callback()
    def _root() -> None:
        pass

    register(app)
    return CliRunner().invoke(app, ["replay", *map(str, args)])


# ---------------------------------------------------------------------------- without SUMO
def test_signal_frames_encode_as_the_protobuf_library_does() -> None:
    enc = SignalEncoder()
    frames = [
        SignalFrame(0, 0.0, ["a", "b"], ["GrGr", "rGrG"], np.array([0, 0]), ["0", "0"]),
        SignalFrame(7, 7.5, ["a", "b"], ["yryr", "rGrG"], np.array([1, 300]), ["0", "online"]),
        SignalFrame(8, -0.0, [], [], np.zeros(0, dtype=np.int64), []),
    ]
    for f in frames:
        data = enc.encode(f)
        msg = SignalFrameMsg(step=f.step, time=f.time, ids=f.ids, states=f.states,
                             phases=f.phases.tolist(), programs=f.programs)  # fmt: skip
        assert data == msg.SerializeToString()
        back = decode_signals(data)
        assert (back.step, back.ids, back.states, back.programs) == (
            f.step, f.ids, f.states, f.programs)  # fmt: skip
        assert back.phases.tolist() == f.phases.tolist()


def test_an_approach_is_green_if_any_of_its_links_is_green() -> None:
    assert approach_colour("rGrr", (0, 1)) == GREEN
    assert approach_colour("ryrg", (0, 3)) == GREEN
    assert approach_colour("ryrG", (0, 1)) == YELLOW
    assert approach_colour("rrGG", (0, 1)) == RED
    assert approach_colour("", (0,)) == UNKNOWN


# ---------------------------------------------------------------------------- real SUMO
@pytest.mark.sumo
def test_logged_signals_equal_what_the_kernel_reported(max_pressure: dict[str, Any]) -> None:
    log = open_log(max_pressure["full"])
    seen = max_pressure["seen"]
    signals = list(log.signals())
    frames = [f.step for f in log.frames()]
    assert [s.step for s in signals] == frames and len(frames) == STEPS + 1
    switched = set()
    for s in signals:
        ids, states, phases, programs = seen[s.step]
        assert (s.ids, s.states, s.phases.tolist(), s.programs) == (ids, states, phases, programs)
        switched.update(states)
    assert len(ids) == 9 and {"GrGr", "rGrG"} <= switched  # the lights did change
    assert any("y" in state for state in switched)


@pytest.mark.sumo
def test_record_every_thins_the_signals_like_the_frames(max_pressure: dict[str, Any]) -> None:
    full = {s.step: s for s in open_log(max_pressure["full"]).signals()}
    thin = open_log(max_pressure["thin"])
    steps = [s.step for s in thin.signals()]
    assert steps == [f.step for f in thin.frames()]
    assert steps and all(step % THIN == 0 for step in steps)
    for s in thin.signals():
        assert s.states == full[s.step].states


@pytest.mark.sumo
def test_logs_without_the_topic_read_and_replay_as_before(
    max_pressure: dict[str, Any], old_log: Path, tmp_path: Path
) -> None:
    old, new = open_log(old_log), open_log(max_pressure["full"])
    assert not old.has_signals and new.has_signals
    assert "/flowrun/traffic_lights" not in old.topics
    assert list(old.signals()) == []
    a, b = summarize(old), summarize(new)
    assert (a.mean_speed, a.logged_steps, a.arrived) == (b.mean_speed, b.logged_steps, b.arrived)
    result = _cli(old_log, "--plot", "all", "--out", tmp_path / "replay")
    assert result.exit_code == 0, result.output
    assert "intersections" not in result.output
    (plots,) = (tmp_path / "replay").iterdir()  # replay's new folder for these plots
    assert (plots / "speeds.png").exists() and not (plots / "signals.png").exists()
    result = _cli(old_log, "--plot", "signals", "--out", tmp_path)
    assert result.exit_code == 1
    assert "no /flowrun/traffic_lights topic" in result.output


@pytest.mark.sumo
def test_replay_plots_signals_and_prints_one_row_per_light(
    max_pressure: dict[str, Any], tmp_path: Path
) -> None:
    result = _cli(max_pressure["full"], "--plot", "signals", "--out", tmp_path / "replay")
    assert result.exit_code == 0, result.output
    (png,) = (tmp_path / "replay").glob("*/signals.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000
    for light in range(9):
        assert f"center{light}" in result.output
    assert "mean delay" in result.output


@pytest.mark.sumo
def test_queues_and_delays_per_intersection_are_plausible(max_pressure: dict[str, Any]) -> None:
    series = signal_series(open_log(max_pressure["full"]))
    assert [s.light for s in series.lights] == [f"center{i}" for i in range(9)]
    assert len(intersection_rows(series)) == 9
    for s in series.lights:
        assert len(s.approaches) == 4  # one lane each way into every junction
        assert s.queue.shape == (STEPS + 1, 4) and (s.queue >= 0).all()
        assert s.queue.max() > 0  # cars do stop at red
        assert 0 < s.mean_delay < STEPS and s.vehicles > 0
        assert set(np.unique(s.signal).tolist()) == {RED, YELLOW, GREEN}
        # a car queues on a red (or yellow) approach, almost never on a green one
        assert s.queue[s.signal == GREEN].sum() < s.queue[s.signal != GREEN].sum()
    # the network-wide queue is the meter's (same definition), split over the approaches
    total = sum(s.queue.sum(axis=1) for s in series.lights)
    assert float(total[1:].mean()) <= max_pressure["metrics"].mean_queue + 1e-9


@pytest.mark.sumo
def test_max_pressure_delays_less_than_fixed_time(
    max_pressure: dict[str, Any], fixed_time: dict[str, Any]
) -> None:
    def delay(path: Path) -> float:
        series = signal_series(open_log(path))
        return float(np.mean([s.mean_delay for s in series.lights]))

    assert delay(max_pressure["full"]) < delay(fixed_time["full"])
    thin = signal_series(open_log(max_pressure["thin"]))
    full = signal_series(open_log(max_pressure["full"]))
    for a, b in zip(thin.lights, full.lights, strict=True):  # a thinned log estimates the same
        assert a.mean_delay == pytest.approx(b.mean_delay, rel=0.25)
