"""Where a training run's wall-clock time goes: start-up, env stepping, policy, updates, evaluation.

:class:`TrainTiming` is filled by a wrapper around the training ``VecEnv`` (time spent waiting
for the env subprocesses), a callback (rollouts vs gradient updates) and the periodic
evaluation; ``flowrun train`` writes it to ``metrics.json`` under ``timing``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from flowrun.training.deps import require

if TYPE_CHECKING:
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import VecEnv


@dataclass
class TrainTiming:
    """Seconds spent in each part of a training run.

    Attributes:
        startup: from the call until learning starts (env subprocesses, model, eval env),
            without the evaluation's all-human baseline episodes (counted in ``evaluation``).
        env_wait: waiting for the env subprocesses' ``step``/``reset`` results.
        rollout: collecting rollouts (env waits, policy inference, callbacks, evaluations).
        update: gradient updates (between the end of a rollout and the next one).
        worker_policy: of ``env_wait``, the policy acting in the env processes (rollouts
            stepped there, :mod:`flowrun.training.rollout`; the slowest process's share).
        evaluation: periodic evaluations (inside ``rollout``).
        checkpoints: saving checkpoints (inside ``rollout``).
        finish: after learning (final model, checkpoint, closing the envs).
        total: the whole call.
        started: ``time.perf_counter()`` at the start of the call.
    """

    startup: float = 0.0
    env_wait: float = 0.0
    worker_policy: float = 0.0
    rollout: float = 0.0
    update: float = 0.0
    evaluation: float = 0.0
    checkpoints: float = 0.0
    finish: float = 0.0
    total: float = 0.0
    started: float = field(default_factory=time.perf_counter)

    @property
    def inference(self) -> float:
        """Rollout time not spent waiting for envs, evaluating or saving: policy + SB3 loop."""
        return max(0.0, self.rollout - self.env_wait - self.evaluation - self.checkpoints)

    @property
    def evaluation_share(self) -> float:
        """Evaluation time over the total (0 when nothing was timed)."""
        return self.evaluation / self.total if self.total > 0 else 0.0

    def parts(self) -> dict[str, float]:
        """The non-overlapping parts, in seconds, whose sum is about ``total``."""
        return {
            "startup": self.startup,
            "env stepping (waiting for the env processes)": self.env_wait,
            "policy inference + SB3 rollout loop": self.inference,
            "gradient updates": self.update,
            "evaluation": self.evaluation,
            "checkpoints": self.checkpoints,
            "finish (final save, close)": self.finish,
        }

    def to_dict(self) -> dict[str, float]:
        """Rounded seconds for ``metrics.json``."""
        data = {
            "startup_s": self.startup,
            "env_wait_s": self.env_wait,
            "worker_policy_s": self.worker_policy,
            "inference_s": self.inference,
            "update_s": self.update,
            "evaluation_s": self.evaluation,
            "checkpoints_s": self.checkpoints,
            "finish_s": self.finish,
            "total_s": self.total,
        }
        out = {k: round(v, 3) for k, v in data.items()}
        out["evaluation_share"] = round(self.evaluation_share, 4)
        return out


def timed_vec_env(venv: VecEnv, timing: TrainTiming) -> VecEnv:
    """Wrap ``venv`` so the time spent in ``step_wait`` adds to ``env_wait``.

    Episode resets inside a rollout happen in ``step_wait`` (the workers reset on their own);
    the first ``reset`` belongs to the start-up.
    """
    vec = require("stable_baselines3.common.vec_env")

    class TimedVecEnv(vec.VecEnvWrapper):  # type: ignore[name-defined]
        def reset(self) -> Any:
            return self.venv.reset()

        def env_method(self, method_name: str, *args: Any, **kwargs: Any) -> Any:
            start = time.perf_counter()  # whole rollouts stepped in the env processes
            try:
                results = self.venv.env_method(method_name, *args, **kwargs)
            finally:
                timing.env_wait += time.perf_counter() - start
            if method_name == "rollout":
                timing.worker_policy += max(segment.policy_s for segment in results)
            return results

        def step_wait(self) -> Any:
            start = time.perf_counter()
            try:
                return self.venv.step_wait()
            finally:
                timing.env_wait += time.perf_counter() - start

    wrapped: VecEnv = TimedVecEnv(venv)
    return wrapped


def timing_callback(timing: TrainTiming) -> BaseCallback:
    """A callback adding rollout time (start to end) and update time (end to next start)."""
    callbacks = require("stable_baselines3.common.callbacks")

    class TimingCallback(callbacks.BaseCallback):  # type: ignore[name-defined]
        def _init_callback(self) -> None:
            self.mark = time.perf_counter()
            self.in_update = False
            self.first = True

        def _lap(self) -> float:
            now = time.perf_counter()
            elapsed, self.mark = now - self.mark, now
            return elapsed

        def _on_rollout_start(self) -> None:
            lap = self._lap()
            if self.first:  # evaluation so far: the baseline episodes, not start-up
                timing.startup = self.mark - timing.started - timing.evaluation
                self.first = False
            elif self.in_update:
                timing.update += lap
            self.in_update = False

        def _on_rollout_end(self) -> None:
            timing.rollout += self._lap()
            self.in_update = True

        def _on_step(self) -> bool:
            return True

        def _on_training_end(self) -> None:
            lap = self._lap()
            if self.in_update:
                timing.update += lap
            elif not self.first:  # stopped inside a rollout
                timing.rollout += lap

    cb: BaseCallback = TimingCallback()
    return cb
