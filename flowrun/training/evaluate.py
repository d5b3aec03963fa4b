"""``evaluate``: roll a trained policy out with :class:`Experiment` beside its baseline.

Both use the same seeds. The baseline
(:func:`~flowrun.training.comparison.comparison_baseline`) is, for one of Flow's benchmarks,
the benchmark's own (its ``--set`` overrides applied to the config, as ``flowrun benchmark``
runs it: e.g. SUMO's actuated lights for the grids); for any other config the same config with
every RL vehicle group driving with the acceleration controller (same parameters, same noise)
of the first human group. Each episode is recorded to MCAP under ``<run>/eval/<timestamp>/``.
"""

from __future__ import annotations

import pickle
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.config.dump import config_to_dict, dump_config
from flowrun.config.model import ExperimentConfig
from flowrun.config.overrides import apply_overrides
from flowrun.config.yamlio import parse_yaml
from flowrun.envs.factory import make_env
from flowrun.errors import ConfigError, TrainingError
from flowrun.experiment.baseline import open_run_log
from flowrun.experiment.metrics import RunMetrics
from flowrun.experiment.runner import Experiment, FrameSink
from flowrun.loading.experiment_checks import sub_path
from flowrun.loading.loader import config_from_dict, load_config, read_config_text
from flowrun.rundir.folders import (
    check_sumo_path,
    exit_code_of,
    mark_done,
    mark_running,
    unique_dir,
    write_json,
)
from flowrun.training.algorithms import algorithm_class
from flowrun.training.comparison import Comparison, comparison_baseline
from flowrun.training.comparison import all_human as all_human
from flowrun.training.trainer import (
    BEST_MODEL,
    BEST_VECNORMALIZE,
    FINAL_MODEL,
    VECNORMALIZE,
    train_section,
)

# progress(label, episode, step)
EvalProgress = Callable[[str, int, int], None]
#: Whether a stop (Ctrl-C/SIGTERM) was asked; may carry ``exit_code`` (128 + the signal).
StopAsked = Callable[[], bool]
MODELS = ("best", "final")


@dataclass
class EvalResult:
    """Metrics of the policy and of its baseline, episode by episode.

    Attributes:
        out_dir: the evaluation folder (``<run>/eval/<timestamp>``).
        model: the model file rolled out.
        policy: one entry per policy episode.
        baseline: one entry per baseline episode (same seeds).
        logs: MCAP files written.
        run_status: the training run's state (:func:`flowrun.rundir.train_state.run_state`):
            anything but ``complete`` means the policy comes from an unfinished run.
        comparison: which baseline (``None``: there is none, ``baseline`` is empty).
    """

    out_dir: Path
    model: Path
    policy: list[RunMetrics]
    baseline: list[RunMetrics]
    logs: list[Path]
    run_status: str = "complete"
    comparison: Comparison | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain data for ``metrics.json`` (``baseline_kind``: ``benchmark`` for a benchmark's
        own baseline, ``all-human``, or ``null`` for none; ``baseline_description``)."""
        known = self.comparison
        return {
            "model": str(self.model),
            "policy": [m.to_dict() for m in self.policy],
            "baseline": [m.to_dict() for m in self.baseline],
            "policy_mean": mean_metrics(self.policy),
            "baseline_mean": mean_metrics(self.baseline),
            "logs": [p.name for p in self.logs],
            "run_status": self.run_status,
            "baseline_kind": None if known is None else known.kind,
            "baseline_description": None if known is None else known.description,
        }


def mean_metrics(rows: Sequence[RunMetrics]) -> dict[str, float]:
    """Mean of each numeric metric over episodes."""
    keys = ("mean_speed", "last_half_mean_speed", "speed_std", "last_half_speed_std",
            "min_speed", "episode_return", "collisions")
    return {k: float(np.mean([getattr(m, k) for m in rows])) if rows else float("nan")
            for k in keys}


def eval_config(
    run_dir: Path, overrides: Sequence[str] = (), config_override: Path | None = None
) -> ExperimentConfig:
    """The run's saved config, merged with an override YAML file, then ``--set`` values."""
    saved = run_dir / "config.yaml"
    if not saved.is_file():
        raise TrainingError(f"{run_dir} is not a run folder (no config.yaml); pass a train run")
    if config_override is None:
        return load_config(saved, overrides)
    data = config_to_dict(load_config(saved))
    source = str(config_override)
    extra, where = parse_yaml(read_config_text(config_override, source), source)
    if not isinstance(extra, dict):
        raise ConfigError("expected a mapping of sections to override", "", source)
    _merge(data, extra)
    apply_overrides(data, list(overrides), where)
    try:
        return config_from_dict(data, source)
    except ConfigError as err:  # at the override file's line when the key is in it
        key = sub_path(err.path)
        if any(key[:n] in where.where for n in range(1, len(key) + 1)):
            raise where.error(err.message, key) from None
        raise


def _merge(base: dict[str, Any], extra: dict[str, Any]) -> None:
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            _merge(base[key], value)
        else:
            base[key] = value


def model_path(run_dir: Path, which: str = "best") -> Path:
    """``best_model.zip`` (falling back to ``final_model.zip``) or ``final_model.zip``."""
    if which not in MODELS:
        raise ConfigError(f"--model must be one of {', '.join(MODELS)}, got '{which}'")
    order = (BEST_MODEL, FINAL_MODEL) if which == "best" else (FINAL_MODEL,)
    for name in order:
        if (run_dir / name).is_file():
            return run_dir / name
    raise TrainingError(
        f"{run_dir} has no {' or '.join(order)}; train first (or resume an interrupted run)"
    )


def evaluate(
    run_dir: Path,
    episodes: int = 1,
    deterministic: bool = True,
    overrides: Sequence[str] = (),
    config_override: Path | None = None,
    model: str = "best",
    progress: EvalProgress | None = None,
    out: Path | None = None,
    should_stop: StopAsked | None = None,
) -> EvalResult:
    """Roll out the trained policy and its baseline, ``episodes`` each.

    Episode ``i`` of both resets with seed ``sim.seed + i``. Writes ``metrics.json`` (with
    ``status``: ``running``, then ``complete`` or ``interrupted``) and the MCAP logs
    (``policy_<i>.mcap``, ``baseline_<i>.mcap``) to ``<out>/<timestamp>-<seed>/``, ``out``
    defaulting to ``<run>/eval``. ``should_stop``: see :func:`run_evaluation`.
    """
    from flowrun.rundir.train_state import run_state

    if episodes < 1:
        raise ConfigError(f"--episodes must be >= 1, got {episodes}")
    cfg = eval_config(run_dir, overrides, config_override)
    tc = train_section(cfg)
    path = model_path(run_dir, model)
    status = run_state(run_dir)
    try:
        policy = algorithm_class(tc.algorithm).load(path, device="cpu")
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as err:
        raise TrainingError(f"cannot load {path}: {err}") from None
    stats = BEST_VECNORMALIZE if path.name == BEST_MODEL else VECNORMALIZE
    normalize = load_normalize(run_dir / stats) if tc.normalize else None

    expected = policy.observation_space.shape

    def act(obs: Any) -> Any:
        if expected is not None and np.shape(obs) != expected:
            raise TrainingError(
                f"the policy in {path.name} takes observations of shape {expected}, but this "
                f"config's environment gives {np.shape(obs)}; evaluate with the config it was "
                "trained on (drop the --set/--config that changes the environment or its cars)"
            )
        x = normalize.normalize_obs(obs) if normalize is not None else obs
        action, _ = policy.predict(x, deterministic=deterministic)
        return action

    head = {"deterministic": deterministic}
    return run_evaluation(
        cfg, run_dir, path, status, head, act, episodes, progress, out, should_stop=should_stop
    )


def run_evaluation(
    cfg: ExperimentConfig,
    run_dir: Path,
    model: Path,
    run_status: str,
    head: dict[str, Any],
    act: Callable[[Any], Any],
    episodes: int,
    progress: EvalProgress | None,
    out: Path | None,
    should_stop: StopAsked | None = None,
) -> EvalResult:
    """The evaluation folder of any backend: the policy's and its baseline's rollouts of
    ``episodes`` episodes each (episode ``i`` seeded ``sim.seed + i``), their MCAP logs,
    ``metrics.json`` (``head`` plus seed, run, model and ``run_status``; ``running`` ->
    ``complete`` / ``interrupted``) and ``status.json``.

    Args:
        model: the model (file or checkpoint) rolled out.
        run_status: the training run's state (:func:`flowrun.rundir.train_state.run_state`).
        act: the policy, ``obs -> action``.
        should_stop: whether Ctrl-C/SIGTERM was received (a
            :class:`~flowrun.rundir.train_state.StopRequest`): an error raised after that
            (the signal also killed netconvert or SUMO) labels the folder ``interrupted``
            with exit code 128 + the signal, not ``failed``.
    """
    compared = comparison_baseline(cfg)  # an error here: before any folder is made
    seed = int(cfg.sim.seed or 0)
    out_dir = _eval_dir(run_dir / "eval" if out is None else out, seed)
    (out_dir / "config.yaml").write_text(dump_config(cfg))
    head = {"seed": seed, "run": str(run_dir), "model": str(model), "run_status": run_status,
            **head}  # fmt: skip
    write_json(out_dir / "metrics.json", {"status": "running", "partial": True, **head})
    mark_running(out_dir)
    logs: list[Path] = []
    try:
        rl = _rollout(cfg, "policy", episodes, seed, act, out_dir, logs, progress)
        human = [] if compared is None else _rollout(
            compared.config, "baseline", episodes, seed, None, out_dir, logs, progress,
            {"baseline_kind": compared.kind},
        )
    except KeyboardInterrupt as err:
        write_json(out_dir / "metrics.json", _stopped(head, logs))
        mark_done(out_dir, "interrupted", exit_code=exit_code_of(err))
        raise
    except Exception as err:
        if should_stop is not None and should_stop():
            write_json(out_dir / "metrics.json", _stopped(head, logs))
            mark_done(out_dir, "interrupted", exit_code=_stop_exit_code(should_stop),
                      error=f"after the stop signal: {type(err).__name__}: {err}")  # fmt: skip
        else:
            mark_done(out_dir, "failed", error=f"{type(err).__name__}: {err}", exit_code=1)
        raise
    result = EvalResult(out_dir, model, rl, human, logs, run_status, compared)
    write_json(out_dir / "metrics.json",
               {"status": "complete", "partial": False, **head, **result.to_dict()})
    mark_done(out_dir, "complete", exit_code=0)
    return result


def _stop_exit_code(should_stop: StopAsked) -> int:
    """128 + the stop's signal (a ``StopRequest`` knows it); 130 (SIGINT) otherwise."""
    code = getattr(should_stop, "exit_code", None)
    return code if isinstance(code, int) else 130


def load_normalize(path: Path) -> Any:
    if not path.is_file():
        raise TrainingError(f"train.normalize is on but {path} is missing")
    try:
        with path.open("rb") as f:
            return pickle.load(f)  # VecNormalize without its env: only the statistics are used
    except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ValueError) as err:
        raise TrainingError(f"cannot read {path}: {err!r}") from None


def _eval_dir(parent: Path, seed: int) -> Path:
    check_sumo_path(parent, "--out")
    return unique_dir(parent / f"{datetime.now(UTC).strftime('%Y%m%d-%H%M%S')}-{seed}")


def _rollout(
    cfg: ExperimentConfig,
    label: str,
    episodes: int,
    seed: int,
    act: Callable[[Any], Any] | None,
    out_dir: Path,
    logs: list[Path],
    progress: EvalProgress | None,
    meta: dict[str, str] | None = None,
) -> list[RunMetrics]:
    """``episodes`` episodes of ``cfg`` logged to ``<label>_<i>.mcap`` (metadata
    ``evaluation: <label>`` and ``meta``)."""
    env = make_env(cfg)  # a multi-agent env is stepped as one joint agent by Experiment

    def sink(run: int) -> FrameSink:
        path = out_dir / f"{label}_{run}.mcap"
        logs.append(path)
        extra = {"evaluation": label, **(meta or {})}
        return open_run_log(path, env, cfg, seed + run, run, extra=extra)

    def on_step(run: int, step: int) -> None:
        if progress is not None:
            progress(label, run, step)

    try:
        experiment = Experiment(env, sink_factory=sink, progress=on_step)
        experiment.run(episodes, int(cfg.env.horizon), rl_actions=act, seed=seed)
    finally:
        env.close()
    return list(experiment.metrics)


def _stopped(head: dict[str, Any], logs: list[Path]) -> dict[str, Any]:
    """``metrics.json`` of an evaluation stopped by Ctrl-C/SIGTERM: what it had, partial."""
    return {"status": "interrupted", "partial": True, **head, "logs": [p.name for p in logs]}
