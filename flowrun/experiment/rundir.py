"""Run folders: ``runs/<config-name>/<timestamp>-<seed>/``, never overwritten.

Each holds the resolved config, the command line, the versions, ``metrics.json`` and logs.
"""

from __future__ import annotations

import json
import platform
import shlex
import sys
from datetime import UTC, datetime
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from flowrun.config.dump import dump_config
from flowrun.config.model import ExperimentConfig
from flowrun.errors import FlowrunError

PACKAGES = (
    "flowrun",
    "eclipse-sumo",
    "libsumo",
    "gymnasium",
    "numpy",
    "mcap",
    "stable-baselines3",
    "torch",
)


def versions() -> dict[str, str]:
    """Versions of Python and the packages a run depends on."""
    found = {"python": platform.python_version(), "platform": platform.platform()}
    for name in PACKAGES:
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            continue
    return found


def unique_dir(base: Path) -> Path:
    """Create ``base`` (or ``base-1``, ``base-2``, ... if taken) and return it: never reuse one."""
    path, n = base, 1
    while True:
        try:
            path.mkdir(parents=True, exist_ok=False)
            return path
        except FileExistsError:
            path = base.with_name(f"{base.name}-{n}")
            n += 1
        except OSError as err:
            raise FlowrunError(f"cannot create folder {path}: {err}") from err


def create_run_dir(
    out: Path, cfg: ExperimentConfig, seed: int, argv: list[str] | None = None
) -> Path:
    """Make a fresh run folder and write the resolved config, command line and versions."""
    stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
    run_dir = unique_dir(out / cfg.name / f"{stamp}-{seed}")
    (run_dir / "config.yaml").write_text(dump_config(cfg))
    command = argv if argv is not None else sys.argv
    (run_dir / "command.txt").write_text(shlex.join(command) + "\n")
    write_json(run_dir / "versions.json", versions())
    return run_dir


def write_json(path: Path, data: Any) -> None:
    """Write JSON atomically (a reader never sees half a file)."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=True, default=str) + "\n")
    tmp.replace(path)
