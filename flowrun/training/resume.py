"""``--resume``: continue a run folder from its last checkpoint without overwriting anything.

Kept across a resume: the earlier config (renamed ``config.before_<steps>.yaml`` when it
changes), the earlier ``metrics.json`` (copied to ``metrics.before_<steps>.json``: its timing
and results), the command lines (appended), the monitor CSVs (renamed
``env_<i>.before_<steps>.monitor.csv``, still found by SB3's ``load_results``), the evaluation
history and the best model with its score (:mod:`flowrun.training.periodic_eval`).
"""

from __future__ import annotations

import shlex
import shutil
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from flowrun.config.dump import dump_config
from flowrun.config.model import ExperimentConfig
from flowrun.errors import TrainingError
from flowrun.loading.loader import load_config
from flowrun.training.callbacks import read_checkpoint_state

MONITOR = "monitor"


def resume_config(run_dir: Path, overrides: Sequence[str] = ()) -> ExperimentConfig:
    """A run folder's saved config with ``--set`` overrides (e.g. more ``total_timesteps``)."""
    config = run_dir / "config.yaml"
    if not config.is_file():
        raise TrainingError(f"{run_dir} is not a run folder (no config.yaml); pass a train run")
    return load_config(config, overrides)


def resume_state(run_dir: Path) -> dict[str, Any]:
    """The last checkpoint's ``state.json``, or an error saying there is none."""
    try:
        state = read_checkpoint_state(run_dir / "checkpoints")
    except ValueError as err:
        raise TrainingError(f"{run_dir}/checkpoints/state.json is damaged ({err})") from None
    if state is None and _never_trained(run_dir):
        return {"timesteps": 0, "model": None, "vecnormalize": None}  # start again in place
    if state is None:
        raise TrainingError(
            f"{run_dir} has no checkpoint to resume from (no checkpoints/state.json); "
            "set train.checkpoint_freq or start a new run"
        )
    if not (run_dir / "checkpoints" / str(state.get("model"))).is_file():
        raise TrainingError(
            f"{run_dir}/checkpoints/state.json names {state.get('model')}, which is missing"
        )
    return state


def _never_trained(run_dir: Path) -> bool:
    """Whether the run stopped before its first step (its ``metrics.json`` says 0 steps)."""
    from flowrun.rundir.train_state import read_metrics

    metrics = read_metrics(run_dir)
    return metrics is not None and metrics.get("timesteps") == 0


def note_resume(
    run_dir: Path, cfg: ExperimentConfig, state: dict[str, Any], argv: list[str] | None
) -> None:
    """Append the command line; keep the earlier config if the resumed one differs, and the
    earlier ``metrics.json`` (its timing) as ``metrics.before_<steps>.json``."""
    command = argv if argv is not None else sys.argv
    with (run_dir / "command.txt").open("a") as f:
        f.write(shlex.join(command) + "\n")
    metrics = run_dir / "metrics.json"
    if metrics.is_file():
        shutil.copyfile(metrics, _free(run_dir / f"metrics.before_{state['timesteps']}.json"))
    text = dump_config(cfg)
    current = run_dir / "config.yaml"
    if current.read_text() != text:
        current.rename(_free(run_dir / f"config.before_{state['timesteps']}.yaml"))
        current.write_text(text)


def keep_monitor_files(run_dir: Path, steps: int) -> list[Path]:
    """Rename the monitor CSVs of the earlier part so the resumed envs start new ones."""
    kept = []
    for csv in sorted((run_dir / MONITOR).glob("env_*.monitor.csv")):
        rank = csv.name.removesuffix(".monitor.csv")
        target = _free(csv.with_name(f"{rank}.before_{steps}.monitor.csv"))
        csv.rename(target)
        kept.append(target)
    return kept


def _free(path: Path) -> Path:
    """``path``, or ``path`` with ``-1``, ``-2``, ... before its suffixes if taken."""
    if not path.exists():
        return path
    name, dot, suffixes = path.name.partition(".")
    n = 1
    while True:
        candidate = path.with_name(f"{name}-{n}{dot}{suffixes}")
        if not candidate.exists():
            return candidate
        n += 1
