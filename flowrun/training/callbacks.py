"""Training callbacks: progress reports, stop requests and periodic checkpoints.

Built lazily (:func:`make_callbacks`) so that importing this module needs no train extra.
A checkpoint is ``checkpoints/model_<steps>.zip`` (+ ``vecnormalize_<steps>.pkl`` and, for
off-policy algorithms, ``replay_buffer.pkl``) and ``checkpoints/state.json`` naming the latest.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flowrun.rundir.folders import write_json
from flowrun.training.deps import require

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.callbacks import BaseCallback

    from flowrun.training.timing import TrainTiming

# progress(timesteps_done, total_timesteps, mean_episode_reward or None)
TrainProgress = Callable[[int, int, float | None], None]
STATE_FILE = "state.json"
# should_stop() -> True once the run was asked to stop (Ctrl-C, SIGTERM)
StopRequested = Callable[[], bool]


def mean_episode_reward(model: BaseAlgorithm) -> float | None:
    """Mean return of the recent finished training episodes (``None`` before the first)."""
    buffer = model.ep_info_buffer
    if not buffer:
        return None
    return float(sum(e["r"] for e in buffer) / len(buffer))


def save_checkpoint(model: BaseAlgorithm, folder: Path, algorithm: str) -> Path:
    """Save the model (and normalisation stats, replay buffer) and point ``state.json`` at it."""
    from flowrun.training.algorithms import OFF_POLICY

    folder.mkdir(parents=True, exist_ok=True)
    steps = int(model.num_timesteps)
    path = folder / f"model_{steps}.zip"
    save_model(model, path)
    state: dict[str, Any] = {"timesteps": steps, "model": path.name, "vecnormalize": None}
    normalize = model.get_vec_normalize_env()
    if normalize is not None:
        stats = folder / f"vecnormalize_{steps}.pkl"
        normalize.save(str(stats))
        state["vecnormalize"] = stats.name
    if algorithm in OFF_POLICY:
        model.save_replay_buffer(folder / "replay_buffer.pkl")  # type: ignore[attr-defined]
        state["replay_buffer"] = "replay_buffer.pkl"
    write_json(folder / STATE_FILE, state)
    return path


def save_model(model: BaseAlgorithm, path: Path) -> None:
    """``model.save`` to a temporary file, then renamed: a killed save leaves no broken zip."""
    tmp = path.with_name(path.stem + ".tmp.zip")
    model.save(tmp)
    tmp.replace(path)


def read_checkpoint_state(folder: Path) -> dict[str, Any] | None:
    """The latest checkpoint's ``state.json``, or ``None`` when there is none."""
    file = folder / STATE_FILE
    if not file.is_file():
        return None
    data: dict[str, Any] = json.loads(file.read_text())
    return data


def make_callbacks(
    algorithm: str,
    checkpoint_dir: Path,
    checkpoint_freq: int,
    progress: TrainProgress | None,
    total_timesteps: int,
    should_stop: StopRequested | None = None,
    timing: TrainTiming | None = None,
) -> list[BaseCallback]:
    """The progress and checkpoint callbacks (frequencies in environment steps, all envs).

    Learning stops at the next step once ``should_stop()`` is true.
    """
    callbacks = require("stable_baselines3.common.callbacks")

    class ProgressCallback(callbacks.BaseCallback):  # type: ignore[name-defined]
        """Reports ``(done, total, mean episode reward)`` after every vectorised step."""

        def _on_step(self) -> bool:
            if progress is not None:
                progress(int(self.num_timesteps), total_timesteps, mean_episode_reward(self.model))
            return should_stop is None or not should_stop()

    class CheckpointCallback(callbacks.BaseCallback):  # type: ignore[name-defined]
        """Saves a checkpoint each time another ``checkpoint_freq`` steps are done."""

        def _init_callback(self) -> None:
            # self.num_timesteps is only set by the first step: a resumed run starts above 0
            self.next_at = _next_multiple(int(self.model.num_timesteps), checkpoint_freq)

        def _on_step(self) -> bool:
            if checkpoint_freq > 0 and self.num_timesteps >= self.next_at:
                start = time.perf_counter()
                save_checkpoint(self.model, checkpoint_dir, algorithm)
                if timing is not None:
                    timing.checkpoints += time.perf_counter() - start
                self.next_at = _next_multiple(int(self.num_timesteps), checkpoint_freq)
            return True

    return [ProgressCallback(), CheckpointCallback()]


def _next_multiple(done: int, every: int) -> int:
    if every <= 0:
        return math.inf  # type: ignore[return-value]
    return (done // every + 1) * every
