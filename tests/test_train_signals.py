"""Real signals sent to ``flowrun train`` / ``flowrun eval`` subprocesses at seeded random moments.

Ctrl-C (SIGINT to the whole process group, as a terminal sends it) and SIGTERM must save a
checkpoint, say ``interrupted`` and exit 130 / 143; ``--resume`` then continues the step
counter. SIGKILL leaves a run that is recognisably cut, never taken for a finished one.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flowrun.recording.reader import open_log
from flowrun.rundir.folders import read_status
from flowrun.rundir.train_state import run_state

pytestmark = pytest.mark.train
pytest.importorskip("stable_baselines3")

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "ring_wave.yaml"
FLOWRUN = str(Path(sys.executable).with_name("flowrun"))
# A tiny ring experiment that would train for minutes if nobody stopped it.
TINY = [
    "env.horizon=200",
    "env.warmup_steps=0",
    "train.n_envs=2",
    "train.algorithm=PPO",
    "train.hyperparams={n_steps: 128, batch_size: 128, n_epochs: 1}",
    "train.policy_kwargs.net_arch=[16, 16]",
    "train.eval_episodes=1",
    "train.eval_freq=256",
    "train.checkpoint_freq=256",
    "train.total_timesteps=1000000",
]


def _sets(items: list[str]) -> list[str]:
    return [arg for item in items for arg in ("--set", item)]


def _start(args: list[str]) -> subprocess.Popen[str]:
    # A session of its own, so a "Ctrl-C" can go to the whole group as a terminal sends it.
    return subprocess.Popen([FLOWRUN, *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True, cwd=ROOT)


def _wait_for(pred: object, proc: subprocess.Popen[str], timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not pred():  # type: ignore[operator]
        assert proc.poll() is None, proc.communicate()[0]
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.05)


def _status(path: Path) -> str | None:
    try:
        return str(json.loads(path.read_text()).get("status"))
    except (OSError, ValueError):
        return None


def _send(proc: subprocess.Popen[str], sig: signal.Signals) -> None:
    if sig == signal.SIGINT:
        os.killpg(proc.pid, sig)  # Ctrl-C reaches every process of the terminal's group
    else:
        os.kill(proc.pid, sig)


def _train_and_signal(out: Path, sig: signal.Signals, seed: int) -> tuple[int, str, Path]:
    """Start a training run, wait until it runs, sleep a seeded random time, signal it."""
    proc = _start(["train", str(CONFIG), "--seed", str(seed), "--out", str(out), *_sets(TINY)])
    runs = out / "ring_wave"
    _wait_for(lambda: runs.is_dir() and any(runs.iterdir())
              and _status(next(runs.iterdir()) / "metrics.json") == "running", proc)
    time.sleep(random.Random(seed).uniform(0.5, 6.0))
    _send(proc, sig)
    output, _ = proc.communicate(timeout=90)
    (run,) = list(runs.iterdir())
    return proc.returncode, output, run


@pytest.mark.parametrize(("sig", "code", "seed"), [(signal.SIGINT, 130, 11),
                                                   (signal.SIGTERM, 143, 12)])
def test_ctrl_c_and_sigterm_save_a_checkpoint_and_resume_continues_the_step_count(
    tmp_path: Path, sig: signal.Signals, code: int, seed: int
) -> None:
    returncode, output, run = _train_and_signal(tmp_path, sig, seed)
    assert returncode == code, output
    assert "Traceback" not in output, output
    assert "interrupted" in output
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["status"] == "interrupted"
    assert run_state(run) == "interrupted"
    shared = read_status(run)  # status.json, as every command writes it
    assert (shared.state, shared.exit_code) == ("interrupted", code)
    state = json.loads((run / "checkpoints" / "state.json").read_text())
    assert state["timesteps"] == metrics["timesteps"]
    assert (run / "checkpoints" / state["model"]).is_file()
    assert not (run / "final_model.zip").exists()  # not mistaken for a finished run
    if sig == signal.SIGTERM:
        return  # resuming is the same after either signal; once is enough for the test time

    total = state["timesteps"] + 512
    done = subprocess.run(
        [FLOWRUN, "train", str(CONFIG), "--resume", str(run),
         "--set", f"train.total_timesteps={total}", "--set", "train.eval_freq=0"],
        capture_output=True, text=True, timeout=120, cwd=ROOT,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    resumed = json.loads((run / "metrics.json").read_text())
    assert resumed["status"] == "complete"
    assert resumed["resumed_from"] == state["timesteps"]
    assert resumed["timesteps"] >= total
    assert (run / "final_model.zip").is_file()


def test_sigkill_leaves_a_cut_run_that_resumes_and_eval_names_it(tmp_path: Path) -> None:
    returncode, _, run = _train_and_signal(tmp_path, signal.SIGKILL, seed=13)
    assert returncode == -signal.SIGKILL
    assert _status(run / "metrics.json") == "running"  # written at the start, never finished
    assert run_state(run) == "cut"
    assert read_status(run).state == "cut"
    state_file = run / "checkpoints" / "state.json"
    # Killed before the first checkpoint (in the start-up), a run starts again in place.
    saved = json.loads(state_file.read_text())["timesteps"] if state_file.is_file() else 0

    if (run / "best_model.zip").is_file():  # killed after the first evaluation
        done = subprocess.run([FLOWRUN, "eval", str(run), "--out", str(tmp_path / "ev")],
                              capture_output=True, text=True, timeout=120, cwd=ROOT)
        assert done.returncode == 0, done.stdout + done.stderr
        assert "cut off" in done.stdout
        (ev,) = list((tmp_path / "ev").iterdir())
        assert json.loads((ev / "metrics.json").read_text())["run_status"] == "cut"

    total = saved + 256
    done = subprocess.run(
        [FLOWRUN, "train", str(CONFIG), "--resume", str(run),
         "--set", f"train.total_timesteps={total}", "--set", "train.eval_freq=0"],
        capture_output=True, text=True, timeout=120, cwd=ROOT,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert json.loads((run / "metrics.json").read_text())["resumed_from"] == saved
    assert run_state(run) == "complete"


@pytest.fixture(scope="module")
def trained_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished tiny training run (in this process)."""
    from flowrun.loading.loader import load_config
    from flowrun.training.trainer import train

    cfg = load_config(CONFIG, [*TINY[:-1], "train.total_timesteps=512", "sim.seed=4"])
    out = tmp_path_factory.mktemp("trained")
    return train(cfg, out=out, argv=["test"]).run_dir


@pytest.mark.parametrize(("sig", "code", "seed"), [(signal.SIGINT, 130, 21),
                                                   (signal.SIGKILL, -9, 23)])
def test_signals_during_eval_leave_readable_logs_and_say_so(
    trained_run: Path, tmp_path: Path, sig: signal.Signals, code: int, seed: int
) -> None:
    out = tmp_path / "ev"
    proc = _start(["eval", str(trained_run), "--episodes", "3", "--seed", str(seed),
                   "--out", str(out), "--set", "env.horizon=3000"])
    _wait_for(lambda: out.is_dir() and any(out.iterdir())
              and any(p.suffix == ".mcap" for p in next(out.iterdir()).iterdir()), proc)
    time.sleep(random.Random(seed).uniform(0.2, 2.0))
    _send(proc, sig)
    output, _ = proc.communicate(timeout=60)
    assert proc.returncode == code, output
    assert "Traceback" not in output
    (ev,) = list(out.iterdir())
    assert ev.name.endswith(f"-{seed}")
    status = _status(ev / "metrics.json")
    assert status == ("running" if sig == signal.SIGKILL else "interrupted")
    assert read_status(ev).state == ("cut" if sig == signal.SIGKILL else "interrupted")
    logs = sorted(ev.glob("*.mcap"))
    assert logs
    for path in logs:  # finished (all but the last complete), or salvaged up to the kill
        log = open_log(path)
        if sig != signal.SIGKILL:
            assert not log.salvaged
        assert sum(1 for _ in log.frames()) >= 1
