"""``--budget MINUTES``: will a training recipe fit the wall time the user gave? Asked up front.

The estimate is arithmetic on a measurement, and says so. The measurement
(:func:`probe_step_rate`) times one episode of one environment of the config (its reset and at
most :data:`PROBE_STEPS` steps), in this process, no learning: the rate the training's
efficiency was measured against. The arithmetic
(:func:`estimate`, a pure function) divides the training steps by that rate times the cores
training can use (``n_envs`` env processes per run, capped by the cores) times the
algorithm's share of it (:func:`training_efficiency`), and adds the evaluation
episodes at the probe's rate and a start-up time per run.

:func:`plan_budget` refuses a recipe whose estimate exceeds the budget, with how to fit it,
and otherwise gives the deadline at which training stops (``flowrun.training.train``'s
``deadline``): the budget's end minus the evaluations that come after training.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from flowrun.config.model import ExperimentConfig
from flowrun.errors import ConfigError, FlowrunError
from flowrun.training.algorithms import OFF_POLICY

#: Most env steps the probe times (one episode from its reset, up to this).
PROBE_STEPS = 3000
#: What the CLI says while the probe runs.
PROBE_TEXT = f"one episode of one env (at most {PROBE_STEPS:,} steps)"
#: Training's env steps/s over (cores used x one env's rate over whole episodes) when the env
#: processes step whole rollouts (ARS's candidates; PPO, TRPO and A2C with an MLP policy): the
#: four benchmarks' recipes measured 0.64-0.79 of it on 2 cores (bench/learning_speed.py,
#: bench/train_throughput.py; docs/training.md).
TRAINING_EFFICIENCY = 0.65
#: The same for off-policy algorithms (SAC, TD3, DDPG), which step through SB3's own loop with
#: a gradient step after every env step: merge0 with SAC's and TD3's defaults measured 0.05
#: and 0.07 (bench/train_throughput.py; 1.7-2.7 ms of updates per env step).
OFF_POLICY_EFFICIENCY = 0.05
#: Seconds a training run spends starting (network, env processes, model) and finishing.
STARTUP_S = 20.0
#: Episodes of each rollout of ``flowrun benchmark --train``'s policy evaluation.
BENCHMARK_EPISODES = 5


@dataclass(frozen=True)
class Workload:
    """What the trainings of one config ask of the machine, in env steps.

    Attributes:
        name: the config's name.
        algorithm: ``train.algorithm``.
        runs: training runs (seeds).
        n_envs: env processes of one run.
        train_steps: training steps, all runs.
        eval_steps: evaluation steps while training runs (all-human reference episodes,
            periodic evaluations, a benchmark's baselines), all runs.
        after_steps: evaluation steps after training (the final evaluation, a benchmark's
            policy evaluation), all runs.
    """

    name: str
    algorithm: str
    runs: int
    n_envs: int
    train_steps: int
    eval_steps: int
    after_steps: int


@dataclass(frozen=True)
class Estimate:
    """The wall time of a :class:`Workload` on this machine.

    Attributes:
        work: what was estimated.
        step_rate: one env's steps/s (the probe).
        cores: the machine's cores.
        cores_used: cores training uses (``n_envs`` x runs, capped by ``cores``).
        train_s: seconds of training.
        eval_s: seconds of evaluation during training.
        after_s: seconds after training (evaluations).
        startup_s: seconds starting and finishing runs.
    """

    work: Workload
    step_rate: float
    cores: int
    cores_used: int
    train_s: float
    eval_s: float
    after_s: float
    startup_s: float

    @property
    def seconds(self) -> float:
        """The whole estimate."""
        return self.train_s + self.eval_s + self.after_s + self.startup_s

    def describe(self) -> str:
        """How it was made, in a few words."""
        w = self.work
        evals = w.eval_steps + w.after_steps
        return (
            f"{w.name}: {w.runs} run(s), {_steps(w.train_steps)} training steps at "
            f"{self.step_rate:,.0f} env steps/s x {self.cores_used} core(s) x "
            f"{training_efficiency(w.algorithm)} ({w.algorithm}) = {_minutes(self.train_s)}, "
            f"{_steps(evals)} evaluation "
            f"steps = {_minutes(self.eval_s + self.after_s)}, start-up "
            f"{_minutes(self.startup_s)}"
        )


def estimate(work: Workload, step_rate: float, cores: int) -> Estimate:
    """The wall time of ``work`` at ``step_rate`` env steps/s per env on ``cores`` cores.

    Training runs on ``min(cores, n_envs * runs)`` cores at :func:`training_efficiency` of the
    env's rate each; evaluation episodes run at the env's rate, ``min(cores, runs)`` at once;
    each run adds :data:`STARTUP_S`, ``min(cores, runs)`` at once.
    """
    if step_rate <= 0 or cores < 1:
        raise ValueError(f"need a positive step rate and cores, got {step_rate}, {cores}")
    used = max(1, min(cores, work.n_envs * work.runs))
    parallel = max(1, min(cores, work.runs))
    return Estimate(
        work=work,
        step_rate=step_rate,
        cores=cores,
        cores_used=used,
        train_s=work.train_steps / (step_rate * used * training_efficiency(work.algorithm)),
        eval_s=work.eval_steps / (step_rate * parallel),
        after_s=work.after_steps / (step_rate * parallel),
        startup_s=STARTUP_S * math.ceil(work.runs / parallel),
    )


def training_efficiency(algorithm: str) -> float:
    """Training's env steps/s over (cores used x one env's rate) for ``algorithm``."""
    return OFF_POLICY_EFFICIENCY if algorithm in OFF_POLICY else TRAINING_EFFICIENCY


def workload(cfg: ExperimentConfig, runs: int, benchmark: bool, done: int = 0) -> Workload:
    """The env steps of training ``cfg`` ``runs`` times (``done`` steps of each already
    trained), with ``flowrun benchmark --train``'s baselines and policy evaluation when
    ``benchmark``."""
    tc = cfg.train
    if tc is None:
        raise ConfigError("this config has no train: section; --budget estimates training")
    horizon = cfg.env.horizon
    episode = int(horizon) + cfg.env.warmup_steps if math.isfinite(horizon) else 0
    left = max(0, tc.total_timesteps - done)
    reference = 1 if tc.best_by == "speed_ratio" else 0  # the all-human episodes, once
    evaluations = reference + left // tc.eval_freq if tc.eval_freq > 0 else 0
    during = runs * evaluations * tc.eval_episodes * episode
    after = runs * 2 * tc.eval_episodes * episode  # the final evaluation: policy and all-human
    if benchmark:
        during += BENCHMARK_EPISODES * episode  # the baselines on the evaluation seeds
        after += runs * 2 * BENCHMARK_EPISODES * episode  # flowrun eval: policy and all-human
    return Workload(cfg.name or "config", tc.algorithm, runs, tc.n_envs, runs * left, during,
                    after)


def probe_step_rate(cfg: ExperimentConfig, steps: int = PROBE_STEPS) -> float:
    """One env's steps/s over one episode with zero actions, its reset included (as training
    resets after every episode; an open network fills with cars as the episode goes on), and at
    most ``steps`` steps of it (the first ``steps`` of a longer or endless episode). The env's
    first reset (building the network, starting SUMO) comes before and is not timed."""
    import numpy as np

    from flowrun.envs.factory import make_env

    horizon = cfg.env.horizon
    count = min(steps, int(horizon)) if math.isfinite(horizon) else steps
    env = make_env(cfg)
    try:
        space = env.action_space
        action = np.zeros(tuple(space.shape or ()), dtype=np.dtype(space.dtype or float))
        env.reset(seed=0)  # the first reset builds the network and starts SUMO: not timed
        start = time.perf_counter()
        env.reset()
        done = 0
        while done < count:
            _, _, terminated, truncated, _ = env.step(action)
            done += 1
            if terminated or truncated:
                break
        return done / max(time.perf_counter() - start, 1e-9)
    finally:
        env.close()


@dataclass(frozen=True)
class BudgetPlan:
    """An estimate that fits the budget, and when training must stop.

    Attributes:
        minutes: the budget.
        estimates: one per config.
        deadline: when training stops at the latest (seconds since the epoch): the budget's
            end minus the evaluations after training.
    """

    minutes: float
    estimates: tuple[Estimate, ...]
    deadline: float

    @property
    def seconds(self) -> float:
        """The whole estimate."""
        return sum(e.seconds for e in self.estimates)

    def describe(self) -> str:
        """The line said before training starts."""
        stop = datetime.fromtimestamp(self.deadline, UTC).strftime("%H:%M:%S UTC")
        return (
            f"estimated {_minutes(self.seconds)} of the {self.minutes:g} min budget "
            f"({_how(self.estimates)}); training stops at {stop} at the latest"
        )

    @property
    def deadline_text(self) -> str:
        """The deadline as ISO 8601 UTC (``train --deadline``)."""
        return datetime.fromtimestamp(self.deadline, UTC).isoformat(timespec="seconds")


def plan_budget(
    works: Sequence[tuple[ExperimentConfig, Workload]],
    minutes: float,
    cores: int | None = None,
    probe: Callable[[ExperimentConfig], float] = probe_step_rate,
    now: float | None = None,
) -> BudgetPlan:
    """Estimate each workload (probing its config's env) and check the sum fits ``minutes``.

    Raises:
        ConfigError: ``minutes`` is not a positive number of minutes.
        FlowrunError: the estimate exceeds the budget (how it was made and how to fit);
            a config trains with RLlib (the budget stops stable-baselines3 training).
    """
    if not minutes > 0 or not math.isfinite(minutes):
        raise ConfigError(f"--budget must be a positive number of minutes, got {minutes:g}")
    for cfg, _ in works:
        if cfg.train is not None and cfg.train.backend == "rllib":
            raise FlowrunError(
                f"{cfg.name}: --budget stops stable-baselines3 training, and this config "
                "trains with train.backend: rllib; drop --budget"
            )
    cores = cores or machine_cores()
    estimates = tuple(estimate(w, probe(cfg), cores) for cfg, w in works)
    total = sum(e.seconds for e in estimates)
    if total > minutes * 60:
        raise FlowrunError(
            f"estimated {_minutes(total)}, over the --budget of {minutes:g} min "
            f"({_how(estimates)}); to fit: {_fits(estimates, minutes)}"
        )
    after = sum(e.after_s for e in estimates)
    start = time.time() if now is None else now
    return BudgetPlan(minutes, estimates, start + minutes * 60 - after)


def train_budget(cfg: ExperimentConfig, minutes: float, resume: Path | None = None) -> BudgetPlan:
    """``flowrun train --budget``: one run of ``cfg`` (what is left of it, with ``resume``).

    Raises:
        ConfigError, FlowrunError: as :func:`plan_budget`.
    """
    done = 0
    if resume is not None:
        from flowrun.rundir.train_state import read_metrics

        done = int((read_metrics(resume) or {}).get("timesteps") or 0)
    return plan_budget([(cfg, workload(cfg, 1, False, done))], minutes)


def benchmark_budget(
    configs: Sequence[Path], sets: Sequence[str], seeds: int, minutes: float
) -> BudgetPlan:
    """``flowrun benchmark --train --budget``: each config trained ``seeds`` times, with the
    benchmark's baselines and policy evaluations.

    Raises:
        ConfigError, FlowrunError: as :func:`plan_budget`.
    """
    from flowrun.loading.loader import load_config

    loaded = [load_config(path, list(sets)) for path in configs]
    return plan_budget([(cfg, workload(cfg, seeds, True)) for cfg in loaded], minutes)


def parse_deadline(text: str) -> float:
    """``train --deadline``'s ISO 8601 time (``2026-11-28T04:00:00+00:00``) as epoch seconds.

    Raises:
        ConfigError: not such a time.
    """
    try:
        when = datetime.fromisoformat(text)
    except ValueError:
        raise ConfigError(
            f"--deadline must be an ISO 8601 time such as 2026-11-28T04:00:00+00:00, got {text!r}"
        ) from None
    return (when if when.tzinfo else when.replace(tzinfo=UTC)).timestamp()


def machine_cores() -> int:
    """The cores this process may run on."""
    affinity = getattr(os, "sched_getaffinity", None)
    return len(affinity(0)) if affinity is not None else os.cpu_count() or 1


def _how(estimates: Sequence[Estimate]) -> str:
    parts = "; ".join(e.describe() for e in estimates)
    return (
        f"{parts}; env steps/s from {PROBE_TEXT}, "
        f"{estimates[0].cores} core(s) here{_load()}"
    )


def _load() -> str:
    """`` at load 5.2`` (the 1-minute load average: the probe ran under it), where known."""
    try:
        return f" at load {os.getloadavg()[0]:.1f}"
    except (AttributeError, OSError):
        return ""


def _fits(estimates: Sequence[Estimate], minutes: float) -> str:
    """Fewer seeds, fewer steps (a number when one config), or a larger budget."""
    total = sum(e.seconds for e in estimates)
    ways = []
    if any(e.work.runs > 1 for e in estimates):
        ways.append("fewer --seeds")
    train = sum(e.train_s for e in estimates)
    room = minutes * 60 - (total - train)
    if len(estimates) == 1 and room > 0 and train > 0:
        work = estimates[0].work
        steps = _round_down(work.train_steps / work.runs * room / train)
        ways.append(f"--set train.total_timesteps={steps}")
    else:
        ways.append("a smaller train.total_timesteps (--set)")
    ways.append(f"--budget {math.ceil(total / 60)}")
    return ", ".join(ways[:-1]) + f" or {ways[-1]}"


def _round_down(steps: float) -> int:
    """``steps`` rounded down to two significant digits (at least 1)."""
    if steps < 1:
        return 1
    scale = 10 ** max(0, int(math.log10(steps)) - 1)
    return int(steps // scale * scale)


def _steps(n: float) -> str:
    return f"{n / 1e6:.3g}M" if n >= 1e6 else f"{n / 1e3:.3g}k" if n >= 1e3 else f"{n:.0f}"


def _minutes(seconds: float) -> str:
    return f"{seconds / 60:.1f} min" if seconds >= 60 else f"{seconds:.0f} s"
