"""Evaluation during training: picks ``best_model.zip`` cheaply and never forgets the best.

Each evaluation rolls the current deterministic policy out for the same seeded episodes, in
this process (the training envs run in subprocesses, so this process has no other SUMO), with
a numpy copy of the policy network (a few microseconds a step instead of SB3's ~100-250 µs
``predict``). Scores are the episode returns in evaluation mode (Flow's ``env.evaluate``:
the mean speed for the ring envs); the best model is the one whose worst episode's last-half
mean speed is highest relative to the baseline of the same episodes
(:meth:`EpisodeRunner.score`; all-human, or a benchmark's own baseline:
:mod:`flowrun.training.comparison`). Envs that vary their network per episode spread the
evaluation episodes over that variation (``evaluation_options``: the ring lengths of the
training range).

The history lives in ``eval_log/evaluations.npz`` (SB3's ``EvalCallback`` format: ``timesteps``,
``results``, ``ep_lengths``, plus ``last_half_speed``); a resumed run continues it and keeps
the best score, so a worse model never replaces ``best_model.zip``.
"""

from __future__ import annotations

import logging
import math
import time
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.errors import TrainingError
from flowrun.training.comparison import comparison_baseline
from flowrun.training.deps import require
from flowrun.training.policy_functions import Act as Act
from flowrun.training.policy_functions import numpy_policy as numpy_policy
from flowrun.training.policy_functions import policy_act
from flowrun.training.policy_functions import torch_policy as torch_policy

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.callbacks import BaseCallback

    from flowrun.training.timing import TrainTiming

log = logging.getLogger(__name__)

EVAL_LOG = "eval_log"
EVALUATIONS = "evaluations.npz"


@dataclass(frozen=True)
class EpisodeScore:
    """One evaluation episode.

    Attributes:
        episode_return: sum of the evaluation-mode rewards.
        length: steps.
        last_half_speed: mean speed of all cars over the second half of the steps, m/s
            (``nan`` when the env reports no ``mean_speed``).
    """

    episode_return: float
    length: int
    last_half_speed: float


class Episodes:
    """The evaluation episodes of a run, reset with the same seeds at every evaluation and
    ranked against the baseline of the same episodes (all-human, or a benchmark's own:
    :func:`~flowrun.training.comparison.comparison_baseline`): :class:`EpisodeRunner`
    (SUMO) or :class:`~flowrun.training.numpy_eval.NumpyEpisodeRunner`.

    Args:
        seeds: one episode per seed, at every evaluation.
        should_stop: polled every step; once true, :meth:`run` gives up.

    Attributes:
        baseline: each seed's baseline last-half mean speed, m/s (``nan`` when unknown);
            set by the subclass.
    """

    baseline: list[float]

    def __init__(
        self,
        seeds: Sequence[int],
        should_stop: Callable[[], bool] | None,
        best_by: str = "speed_ratio",
    ) -> None:
        self.seeds = tuple(seeds)
        self.should_stop = should_stop
        self.best_by = best_by

    @property
    def needs_baseline(self) -> bool:
        """Whether :meth:`score` compares with the baseline's episodes (``speed_ratio``)."""
        return self.best_by == "speed_ratio"

    def score(self, scores: Sequence[EpisodeScore]) -> float:
        """What picks the best model. ``best_by: return``: the mean evaluation-mode return (a
        benchmark's metric). ``speed_ratio``: the worst episode's last-half mean speed as a
        fraction of the baseline's on the same seed (rings of different lengths then
        count alike, and a policy must be good on every one of them: the mean let a policy that
        stops the AV on short rings win on its long ones); the mean return when the env
        reports no speeds."""
        if not self.needs_baseline:
            return float(np.mean([s.episode_return for s in scores]))
        ratios = [s.last_half_speed / b for s, b in zip(scores, self.baseline, strict=True)]
        if all(math.isfinite(r) for r in ratios) and all(b > 0 for b in self.baseline):
            return float(min(ratios))
        return float(np.mean([s.episode_return for s in scores]))

    def run(
        self, act: Act, normalize: Callable[[np.ndarray], np.ndarray] | None
    ) -> list[EpisodeScore] | None:
        """One episode per seed with the policy (observations normalised first); ``None``
        when ``should_stop`` became true on the way."""
        raise NotImplementedError

    def close(self) -> None:
        """Release the simulation, if any (idempotent)."""


class EpisodeRunner(Episodes):
    """The evaluation env in this process (SUMO)."""

    def __init__(
        self,
        cfg: ExperimentConfig,
        seeds: Sequence[int],
        should_stop: Callable[[], bool] | None = None,
        best_by: str = "speed_ratio",
    ) -> None:
        """Build the env of ``cfg`` (evaluation mode is the caller's choice); see
        :class:`Episodes` for the other arguments."""
        from flowrun.envs.factory import make_env

        super().__init__(seeds, should_stop, best_by)
        nan = [math.nan] * len(self.seeds)
        self.baseline = self._baseline(cfg) if self.needs_baseline else nan
        self.env = make_env(cfg)  # after the baseline's env is closed: one SUMO a process
        self.options = _spread_options(self.env, len(self.seeds))

    def _baseline(self, cfg: ExperimentConfig) -> list[float]:
        """Last-half mean speed of each seed's episode of the baseline
        (:func:`~flowrun.training.comparison.comparison_baseline`: the benchmark's own, else
        the AVs driven like the humans)."""
        from flowrun.envs.factory import make_env

        baseline = comparison_baseline(cfg)
        if baseline is None:  # no human group to copy: scores fall back to returns
            return [math.nan] * len(self.seeds)
        env = make_env(baseline.config)
        try:
            spread = _spread_options(env, len(self.seeds))  # as the policy's episodes
            runs = [
                play_episode(env, seed, None, None, self.should_stop, options)
                for seed, options in zip(self.seeds, spread, strict=True)
            ]
            return [math.nan if r is None else r.last_half_speed for r in runs]
        finally:
            env.close()

    def run(
        self, act: Act, normalize: Callable[[np.ndarray], np.ndarray] | None
    ) -> list[EpisodeScore] | None:
        """One episode per seed with the given policy; observations normalised first.

        Returns ``None`` when ``should_stop`` became true on the way.
        """
        scores = []
        for seed, options in zip(self.seeds, self.options, strict=True):
            score = play_episode(self.env, seed, act, normalize, self.should_stop, options)
            if score is None:
                return None
            scores.append(score)
        return scores

    def close(self) -> None:
        """Stop the env's simulation (idempotent)."""
        self.env.close()


def play_episode(
    env: Any,
    seed: int,
    act: Act | None,
    normalize: Callable[[np.ndarray], np.ndarray] | None,
    stop: Callable[[], bool] | None = None,
    options: dict[str, Any] | None = None,
) -> EpisodeScore | None:
    """One episode reset with ``seed`` (and reset ``options``); ``act`` ``None`` sends no RL
    action. ``None`` when ``stop()`` became true on the way."""
    obs, _ = env.reset(seed=seed, options=options or None)
    total, speeds, done = 0.0, [], False
    while not done:
        if stop is not None and stop():
            return None
        action = None
        if act is not None:
            x = np.asarray(obs, dtype=np.float32)
            action = act(normalize(x[None])[0] if normalize is not None else x)
        obs, reward, terminated, truncated, info = env.step(action)
        total += float(reward)
        speeds.append(float(info.get("mean_speed", math.nan)))
        done = terminated or truncated
    half = speeds[len(speeds) // 2 :]
    return EpisodeScore(total, len(speeds), float(np.mean(half)))


def _spread_options(env: Any, episodes: int) -> list[dict[str, Any]]:
    """The env's reset options for ``episodes`` evaluation episodes (its
    ``evaluation_options``, e.g. ring lengths spread over the trained range), else none."""
    spread = getattr(getattr(env, "unwrapped", env), "evaluation_options", None)
    return list(spread(episodes)) if callable(spread) else [{} for _ in range(episodes)]


@dataclass
class EvalHistory:
    """The evaluations of a run so far (``eval_log/evaluations.npz``)."""

    timesteps: list[int] = field(default_factory=list)
    results: list[list[float]] = field(default_factory=list)
    ep_lengths: list[list[int]] = field(default_factory=list)
    last_half_speed: list[list[float]] = field(default_factory=list)
    score: list[float] = field(default_factory=list)

    @property
    def best(self) -> float:
        """The best score so far (``-inf`` before the first evaluation)."""
        return max(self.score, default=-math.inf)

    def add(self, timesteps: int, scores: Sequence[EpisodeScore], score: float) -> None:
        """Append one evaluation with the score that ranks it."""
        self.score.append(score)
        self.timesteps.append(timesteps)
        self.results.append([s.episode_return for s in scores])
        self.ep_lengths.append([s.length for s in scores])
        self.last_half_speed.append([s.last_half_speed for s in scores])

    @classmethod
    def load(cls, path: Path) -> EvalHistory:
        """The history saved at ``path`` (empty when there is none)."""
        if not path.is_file():
            return cls()
        try:
            return cls._read(path)
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as err:
            raise TrainingError(
                f"{path} is damaged ({err}); move it away to start a new evaluation history"
            ) from None

    @classmethod
    def _read(cls, path: Path) -> EvalHistory:
        with np.load(path) as data:
            results = data["results"].tolist()
            if "last_half_speed" in data:
                speeds = data["last_half_speed"].tolist()
            else:  # written by SB3's EvalCallback
                speeds = [[math.nan] * len(r) for r in results]
            # SB3's files ranked by mean return (much larger than a speed ratio: kept best)
            score = data["score"].tolist() if "score" in data else [float(np.mean(r))
                                                                     for r in results]
            return cls(
                [int(t) for t in data["timesteps"]], results, data["ep_lengths"].tolist(), speeds,
                score,
            )

    def save(self, path: Path) -> None:
        """Write atomically (an interrupted save leaves the previous file)."""
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.stem + ".tmp.npz")
        np.savez(
            tmp,
            timesteps=np.asarray(self.timesteps, dtype=np.int64),
            results=np.asarray(self.results, dtype=np.float64),
            ep_lengths=np.asarray(self.ep_lengths, dtype=np.int64),
            last_half_speed=np.asarray(self.last_half_speed, dtype=np.float64),
            score=np.asarray(self.score, dtype=np.float64),
        )
        tmp.replace(path)


def make_periodic_eval_callback(
    runner: Episodes,
    run_dir: Path,
    eval_freq: int,
    best_model: str,
    best_stats: str,
    timing: TrainTiming | None = None,
) -> BaseCallback:
    """A callback that evaluates every ``eval_freq`` environment steps (all envs).

    A new best mean return saves the model as ``run_dir/best_model`` and, with
    ``VecNormalize``, the statistics it was evaluated with as ``run_dir/best_stats``.
    """
    callbacks = require("stable_baselines3.common.callbacks")
    history_path = run_dir / EVAL_LOG / EVALUATIONS
    history = EvalHistory.load(history_path)

    class PeriodicEval(callbacks.BaseCallback):  # type: ignore[name-defined]
        """Evaluates at each multiple of ``eval_freq`` steps; keeps the best model."""

        def _init_callback(self) -> None:
            done = int(self.model.num_timesteps)  # self.num_timesteps is set by the first step
            self.next_at = (done // eval_freq + 1) * eval_freq

        def _on_step(self) -> bool:
            if self.num_timesteps < self.next_at:
                return True
            self.next_at = (int(self.num_timesteps) // eval_freq + 1) * eval_freq
            start = time.perf_counter()
            try:
                return self.evaluate()
            finally:
                if timing is not None:
                    timing.evaluation += time.perf_counter() - start

        def evaluate(self) -> bool:
            normalize = self.model.get_vec_normalize_env()
            scores = runner.run(
                policy_act(self.model), None if normalize is None else normalize.normalize_obs
            )
            if scores is None:
                return False  # asked to stop
            previous_best = history.best
            mean = runner.score(scores)
            history.add(int(self.num_timesteps), scores, mean)
            _log_evaluation(self.logger, history)
            if mean <= previous_best:
                history.save(history_path)
                return True
            _save_best(self.model, normalize, history, history_path,
                      run_dir / best_model, run_dir / best_stats)  # fmt: skip
            log.info("new best evaluation %.3f at %d steps", mean, self.num_timesteps)
            return True

    cb: BaseCallback = PeriodicEval()
    return cb


def _log_evaluation(logger: Any, history: EvalHistory) -> None:
    """The last evaluation's mean return, last-half speed and score to SB3's logger."""
    logger.record("eval/mean_reward", float(np.mean(history.results[-1])))
    logger.record("eval/last_half_speed", float(np.mean(history.last_half_speed[-1])))
    logger.record("eval/score", history.score[-1])


def _save_best(
    model: BaseAlgorithm,
    normalize: Any,
    history: EvalHistory,
    history_path: Path,
    model_path: Path,
    stats_path: Path,
) -> None:
    """A new best model, the ``VecNormalize`` statistics it was evaluated with (if any) and
    the evaluation history that ranks it: both files first under temporary names, then
    renamed, so a kill leaves a matching pair."""
    tmp_model = model_path.with_name(model_path.stem + ".tmp.zip")
    model.save(tmp_model)
    tmp_stats = stats_path.with_name(stats_path.name + ".tmp")
    if normalize is not None:
        normalize.save(str(tmp_stats))
    history.save(history_path)
    tmp_model.replace(model_path)
    if normalize is not None:
        tmp_stats.replace(stats_path)
