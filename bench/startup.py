"""CPU time of flowrun's start-up commands: each run as a new process, the fastest of N.

    .venv/bin/python bench/startup.py [--repeats 5]

CPU time (user + system of the child process) rather than wall time, so the machine's load
moves the numbers less; the fastest of the repeats is the one least disturbed. ``python -c
pass`` is the floor every command pays. Each command runs once first, not counted, to write
its compiled bytecode (to a temporary ``PYTHONPYCACHEPREFIX``, even under
``PYTHONDONTWRITEBYTECODE``), so the numbers are those of an installed package, not of
compiling flowrun's sources at every start.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FLOWRUN = [sys.executable, "-m", "flowrun.cli.main"]
COMMANDS: list[tuple[str, list[str]]] = [
    ("python -c pass", [sys.executable, "-c", "pass"]),
    ("flowrun --version", [*FLOWRUN, "--version"]),
    ("flowrun --help", [*FLOWRUN, "--help"]),
    ("flowrun baseline --help", [*FLOWRUN, "baseline", "--help"]),
    ("flowrun list envs", [*FLOWRUN, "list", "envs"]),
    ("flowrun list networks", [*FLOWRUN, "list", "networks"]),
    ("flowrun list controllers", [*FLOWRUN, "list", "controllers"]),
    ("flowrun validate configs/sugiyama.yaml", [*FLOWRUN, "validate", "configs/sugiyama.yaml"]),
    ("flowrun validate configs/merge.yaml (train:)", [*FLOWRUN, "validate", "configs/merge.yaml"]),
    ("python -c 'import stable_baselines3'", [sys.executable, "-c", "import stable_baselines3"]),
]


def cpu_seconds(cmd: list[str], pycache: str) -> float:
    """User + system CPU seconds of one run of ``cmd`` (its output discarded), its bytecode
    in ``pycache``; NaN if it fails."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONPYCACHEPREFIX": pycache}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        return math.nan
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print(f"load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"{'command':<46} {'CPU s (min)':>11} {'median':>7}")
    with tempfile.TemporaryDirectory(prefix="flowrun-pyc-") as pycache:
        for label, cmd in COMMANDS:
            cpu_seconds(cmd, pycache)  # writes the bytecode
            times = sorted(cpu_seconds(cmd, pycache) for _ in range(args.repeats))
            print(f"{label:<46} {times[0]:>11.2f} {times[len(times) // 2]:>7.2f}")


if __name__ == "__main__":
    main()
