"""An evaluation whose child process (netconvert, SUMO) dies of the same Ctrl-C/SIGTERM that
stops ``flowrun eval`` is ``interrupted`` (exit 130/143) in its ``status.json``, not
``failed``; the same error with no stop asked is still a failure."""

from __future__ import annotations

import importlib
import json
import signal
from pathlib import Path
from typing import Any

import pytest

from flowrun.errors import SimulationError
from flowrun.loading.loader import load_config
from flowrun.rundir.folders import read_status
from flowrun.rundir.train_state import StopRequest

ROOT = Path(__file__).resolve().parent.parent
ev = importlib.import_module("flowrun.training.evaluate")  # the package exports a function of
# that name


def netconvert_killed(*args: Any, **kwargs: Any) -> Any:
    raise SimulationError("netconvert failed on ring.edg.xml: ")  # what a killed child leaves


def evaluate_with(stop: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setattr(ev, "_rollout", netconvert_killed)
    cfg = load_config(ROOT / "configs" / "ring_wave.yaml")
    run_dir = tmp_path / "run"
    with pytest.raises(SimulationError):
        ev.run_evaluation(cfg, run_dir, run_dir / "final_model.zip", "complete", {},
                          lambda obs: obs, 1, None, None, should_stop=stop)  # fmt: skip
    (folder,) = (run_dir / "eval").iterdir()
    return folder


@pytest.mark.parametrize(("signum", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_error_after_a_stop_signal_is_an_interruption(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, signum: int, code: int
) -> None:
    stop = StopRequest()
    stop.signal(signum)
    folder = evaluate_with(stop, tmp_path, monkeypatch)
    status = read_status(folder)
    assert (status.state, status.exit_code) == ("interrupted", code)
    assert status.error is not None and "netconvert failed" in status.error
    assert json.loads((folder / "metrics.json").read_text())["status"] == "interrupted"


@pytest.mark.parametrize("stop", [None, StopRequest()])
def test_the_same_error_without_a_stop_is_a_failure(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, stop: StopRequest | None
) -> None:
    folder = evaluate_with(stop, tmp_path, monkeypatch)
    status = read_status(folder)
    assert (status.state, status.exit_code) == ("failed", 1)
    assert status.error == "SimulationError: netconvert failed on ring.edg.xml: "
    assert json.loads((folder / "metrics.json").read_text())["status"] == "running"
