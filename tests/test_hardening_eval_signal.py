"""A real Ctrl-C while ``flowrun eval`` waits for netconvert: the terminal's SIGINT reaches
netconvert too, which dies; the evaluation still says ``interrupted`` (exit 130), not
``failed``. netconvert is made slow (a ring drawn with 20,000 points per edge) and the signal
is sent once it runs, so the timing does not depend on the machine's speed."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flowrun.rundir.folders import read_status

pytestmark = [pytest.mark.train, pytest.mark.sumo]
pytest.importorskip("stable_baselines3")

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "ring_wave.yaml"
FLOWRUN = str(Path(sys.executable).with_name("flowrun"))
TINY = [
    "env.horizon=100",
    "train.n_envs=1",
    "train.algorithm=PPO",
    "train.hyperparams={n_steps: 64, batch_size: 64, n_epochs: 1}",
    "train.policy_kwargs.net_arch=[8]",
    "train.eval_freq=1000000",
    "train.checkpoint_freq=1000000",
    "train.total_timesteps=64",
    "sim.seed=2",
]


def children(pid: int) -> list[tuple[int, str]]:
    """(pid, command name) of the processes whose parent is ``pid`` (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        name = stat[stat.index("(") + 1 : stat.rindex(")")]
        if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
            found.append((int(entry.name), name))
    return found


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_ctrl_c_that_kills_netconvert_leaves_an_interrupted_evaluation(tmp_path: Path) -> None:
    from flowrun.loading.loader import load_config
    from flowrun.training.trainer import train

    run = train(load_config(CONFIG, TINY), out=tmp_path / "runs", argv=["test"]).run_dir
    out = tmp_path / "ev"
    proc = subprocess.Popen(
        [FLOWRUN, "eval", str(run), "--out", str(out), "--set", "network.resolution=20000"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True,
    )  # fmt: skip
    deadline = time.monotonic() + 120
    while not any(name == "netconvert" for _, name in children(proc.pid)):
        assert proc.poll() is None, proc.communicate()[0]
        assert time.monotonic() < deadline, "netconvert never started"
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: eval and netconvert
    output, _ = proc.communicate(timeout=120)
    assert proc.returncode == 130, output
    assert "Traceback" not in output and "interrupted" in output
    (folder,) = out.iterdir()
    status = read_status(folder)
    assert (status.state, status.exit_code) == ("interrupted", 130)
    assert json.loads((folder / "metrics.json").read_text())["status"] == "interrupted"
