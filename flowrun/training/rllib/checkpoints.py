"""RLlib checkpoints of a run folder: ``checkpoints/iter_<n>/`` with ``checkpoints/state.json``
naming the latest, ``best_checkpoint/`` and ``final_checkpoint/``, each written under a
temporary name first."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

from flowrun.errors import TrainingError
from flowrun.rundir.folders import write_json

BEST_CHECKPOINT = "best_checkpoint"
FINAL_CHECKPOINT = "final_checkpoint"
STATE_FILE = "state.json"


def save_tree(algo: Any, path: Path) -> None:
    """Save an RLlib checkpoint to ``path``, replacing an earlier one only once it is written."""
    tmp = path.with_name(f".{path.name}.tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    algo.save_to_path(str(tmp.resolve()))
    old = path.with_name(f".{path.name}.old")
    if path.exists():
        path.rename(old)
    tmp.rename(path)
    shutil.rmtree(old, ignore_errors=True)


def save_checkpoint(
    algo: Any, ckpt_dir: Path, iteration: int, timesteps: int, best: float | None
) -> Path:
    """Save ``checkpoints/iter_<n>/`` and point ``checkpoints/state.json`` at it."""
    name = f"iter_{int(iteration):06d}"
    save_tree(algo, ckpt_dir / name)
    write_json(
        ckpt_dir / STATE_FILE,
        {"checkpoint": name, "iteration": int(iteration), "timesteps": int(timesteps),
         "best_return": best},
    )  # fmt: skip
    return ckpt_dir / name


def read_state(run_dir: Path) -> dict[str, Any]:
    """The latest checkpoint of a run folder (``checkpoints/state.json``).

    Raises:
        TrainingError: not a run folder, or no checkpoint.
    """
    if not (run_dir / "config.yaml").is_file():
        raise TrainingError(f"{run_dir} is not a run folder (no config.yaml); pass a train run")
    path = run_dir / "checkpoints" / STATE_FILE
    try:
        state = json.loads(path.read_text())
    except (OSError, ValueError):
        raise TrainingError(
            f"{run_dir} has no RLlib checkpoint to resume from (no readable "
            "checkpoints/state.json); set train.checkpoint_freq or start a new run"
        ) from None
    if not (run_dir / "checkpoints" / str(state.get("checkpoint"))).is_dir():
        raise TrainingError(f"{path} names a checkpoint that is missing: {state.get('checkpoint')}")
    return dict(state)


def keep_checkpoints(
    algo: Any,
    run_dir: Path,
    freq: int,
    iteration: int,
    steps: tuple[int, int],
    score: float | None,
    best: float | None,
) -> float | None:
    """After an iteration that took the env steps from ``steps[0]`` to ``steps[1]``: a better
    evaluation ``score`` is saved as ``best_checkpoint/``, and a checkpoint every ``freq``
    steps; returns the best score so far."""
    if score is not None and (best is None or score > best):
        best = score
        save_tree(algo, run_dir / BEST_CHECKPOINT)
    before, done = steps
    if freq > 0 and done // freq > before // freq:
        save_checkpoint(algo, run_dir / "checkpoints", iteration, done, best)
    return best
