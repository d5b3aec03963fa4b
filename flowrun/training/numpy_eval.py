"""Evaluation during training on the numpy ring backend (``train.eval_backend: numpy``).

The same episodes as :class:`~flowrun.training.periodic_eval.EpisodeRunner` plays on SUMO —
same reset seeds, same ring lengths (the env's ``evaluation_options``), evaluation-mode
rewards, the all-human baseline — but every episode of an evaluation is one ring of a
:class:`~flowrun.fastring.rings.FastRings` batch, stepped together with the policy applied to
all rings at once. The numpy rings equal SUMO's to 1e-9 m/s (``tests/test_fastring_sumo.py``),
so the scores that pick ``best_model.zip`` are SUMO's up to rounding, at about a fifth of the
cost (``bench/eval_backends.py``: 3 ring episodes, 5.4x cheaper than on SUMO per evaluation).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.errors import ConfigError
from flowrun.fastring.plan import NumpyBackendRefusal, RingPlan, ring_plan
from flowrun.fastring.rings import FastRings
from flowrun.fastring.tasks import RingTask
from flowrun.training.comparison import comparison_baseline
from flowrun.training.periodic_eval import Act, Episodes, EpisodeScore

EVAL_BACKEND_PATH = "train.eval_backend"


def numpy_eval_plan(cfg: ExperimentConfig) -> RingPlan:
    """The numpy backend's plan of ``cfg``'s evaluation episodes (evaluate mode).

    Raises:
        ConfigError: at ``train.eval_backend`` when the numpy backend cannot run ``cfg``.
    """
    eval_cfg = replace(cfg, env=replace(cfg.env, evaluate=True))
    try:
        return ring_plan(replace(eval_cfg, sim=replace(cfg.sim, backend="numpy")))
    except NumpyBackendRefusal as err:
        where = f" ({err.path})" if err.path else ""
        raise ConfigError(
            f"the numpy evaluation backend {err.what}{where}; use train.eval_backend: sumo "
            "for this config",
            EVAL_BACKEND_PATH,
            cfg.source or "",
        ) from None


class NumpyEpisodeRunner(Episodes):
    """:class:`~flowrun.training.periodic_eval.EpisodeRunner`'s episodes on numpy rings."""

    def __init__(
        self,
        cfg: ExperimentConfig,
        seeds: Sequence[int],
        should_stop: Callable[[], bool] | None = None,
        best_by: str = "speed_ratio",
    ) -> None:
        """Plan ``cfg`` (evaluation mode is set here) and run the all-human baseline; see
        :class:`~flowrun.training.periodic_eval.Episodes` for the other arguments."""
        from flowrun.envs.factory import env_class
        from flowrun.envs.ring.wave_attenuation import spread_lengths

        super().__init__(seeds, should_stop, best_by)
        self._start: FastRings | None = None
        self.plan = numpy_eval_plan(cfg)
        # spread over the drawn lengths as the SUMO env's evaluation_options spreads them
        bounds, n = self.plan.bounds, len(self.seeds)
        self.lengths: list[float | None] = [None] * n
        if bounds is not None and hasattr(env_class(cfg), "evaluation_options"):
            self.lengths = [float(x) for x in spread_lengths(bounds, n)]
        self.baseline = self._baseline(cfg) if self.needs_baseline else [math.nan] * n

    def _baseline(self, cfg: ExperimentConfig) -> list[float]:
        """Last-half mean speed of each seed's baseline episode (``nan`` when unknown):
        :func:`~flowrun.training.comparison.comparison_baseline`, all-human on a ring."""
        nan = [math.nan] * len(self.seeds)
        baseline = comparison_baseline(cfg)
        if baseline is None:  # no human group to copy: scores fall back to returns
            return nan
        # not refused, as the policy's plan was not: only the RL groups change, to the human
        # controller that plan already runs. runs None: asked to stop (run() gives up too)
        runs = self._play(numpy_eval_plan(baseline.config), None, None)
        return nan if runs is None else [r.last_half_speed for r in runs]

    def run(
        self, act: Act, normalize: Callable[[np.ndarray], np.ndarray] | None
    ) -> list[EpisodeScore] | None:
        """Every seed's episode with the policy (``act`` takes a batch of observations);
        ``None`` when ``should_stop`` became true on the way."""
        return self._play(self.plan, act, normalize)

    def _warmed_up(self, plan: RingPlan) -> FastRings:
        """The rings of every seed's episode after its reset and warm-up (which no policy
        acts in); for the policy's plan made once, then copied for each evaluation."""
        if plan is self.plan and self._start is not None:
            return copy.deepcopy(self._start, memo={id(plan): plan})
        b = len(self.seeds)
        rings = FastRings(plan, b)
        rings.reset(np.arange(b), list(self.seeds), self.lengths)
        if plan is not self.plan:
            return rings
        self._start = rings
        return copy.deepcopy(rings, memo={id(plan): plan})

    def _play(
        self,
        plan: RingPlan,
        act: Act | None,
        normalize: Callable[[np.ndarray], np.ndarray] | None,
    ) -> list[EpisodeScore] | None:
        b = len(self.seeds)
        rings, task = self._warmed_up(plan), RingTask(plan)
        obs = task.observe(rings)
        alive = np.ones(b, dtype=bool)
        steps = np.zeros(b, dtype=np.int64)
        total = np.zeros(b)
        speeds = np.empty((plan.horizon, b))
        for t in range(plan.horizon):
            if self.should_stop is not None and self.should_stop():
                return None
            if act is None:
                actions = np.zeros((b, 0))
            else:
                actions = act(normalize(obs) if normalize is not None else obs)
            applied = task.clip(actions)
            crashed = rings.step(applied)
            rewards = task.rewards(rings, applied, crashed)
            state = rings.state
            assert state is not None
            speeds[t] = state.speed.mean(axis=0)
            total += np.where(alive, rewards, 0.0)
            steps += alive
            alive &= ~crashed  # a collision ends that ring's episode
            if not alive.any():
                break
            obs = task.observe(rings)
        scores = []
        for i in range(b):
            n = int(steps[i])
            half = speeds[n // 2 : n, i]
            scores.append(EpisodeScore(float(total[i]), n, float(np.mean(half))))
        return scores
