"""``train_rllib``: a config's ``train:`` section -> RLlib PPO -> the run folder SB3 runs write.

Run folder (``runs/<name>/<timestamp>-<seed>/``): ``config.yaml``, ``command.txt``,
``versions.json`` (with Ray's version), ``tensorboard/`` (RLlib's main metrics per iteration),
``progress.jsonl`` (one line per iteration: env and agent steps, mean episode return and
length), ``policies.json`` (multi-agent: agent -> policy),
``checkpoints/iter_<n>/`` (RLlib checkpoints) with ``checkpoints/state.json`` (the latest),
``best_checkpoint/`` (best evaluation return, when evaluating during training),
``final_checkpoint/``, ``metrics.json``; the final evaluation goes under ``eval/``
(:func:`flowrun.training.rllib.evaluate.evaluate_rllib`).
"""

from __future__ import annotations

import json
import logging
import math
import re
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

from flowrun.config.model import ExperimentConfig, TrainConfig
from flowrun.rundir.folders import (
    exit_code_of,
    mark_done,
    mark_running,
    start_run,
    write_json,
)
from flowrun.rundir.train_state import RunLock
from flowrun.training.callbacks import TrainProgress
from flowrun.training.resume import note_resume
from flowrun.training.rllib.checkpoints import (
    FINAL_CHECKPOINT,
    keep_checkpoints,
    read_state,
    save_checkpoint,
    save_tree,
)
from flowrun.training.rllib.cluster import RaySession, ray_session
from flowrun.training.rllib.deps import require_ray
from flowrun.training.rllib.options import (
    EPISODE_AGENT,
    build_ppo_config,
    check_train_config,
    env_runners,
    steps_per_iteration,
)
from flowrun.training.trainer import TrainResult, train_section, train_seed

log = logging.getLogger(__name__)

#: RLlib result entries written to TensorBoard (paths joined with ``/``).
TB_KEYS = re.compile(
    r"^(env_runners/(episode_(return|len)_(mean|min|max)|num_episodes)"
    r"|evaluation/env_runners/episode_(return|len)_mean"
    r"|learners/[^/]+/(policy_loss|vf_loss|entropy|mean_kl_loss|total_loss|vf_explained_var)"
    r"|num_env_steps_sampled_lifetime|time_this_iter_s)$"
)


def train_rllib(
    cfg: ExperimentConfig,
    out: Path = Path("runs"),
    resume_dir: Path | None = None,
    progress: TrainProgress | None = None,
    argv: list[str] | None = None,
    should_stop: Callable[[], bool] | None = None,
    ray_address: str | None = None,
) -> TrainResult:
    """Train the config's policy with RLlib's PPO and write the run folder.

    Trains until ``train.total_timesteps`` env steps are sampled (whole iterations of
    RLlib's train batch). Multi-agent envs train ``train.policies`` policies.

    Args:
        cfg: the experiment, with a ``train:`` section (``backend: rllib``). To resume, pass
            the run folder's config, possibly with a larger ``train.total_timesteps``.
        out: parent of new run folders.
        resume_dir: an earlier run folder to continue from its last checkpoint (RLlib's
            iteration and step counters continue).
        progress: called with ``(timesteps done, total, mean episode return)`` per iteration.
        argv: the command line saved in ``command.txt``.
        should_stop: polled after every iteration; once true, a checkpoint is saved and the
            run ends ``interrupted`` (the CLI's Ctrl-C/SIGTERM request).
        ray_address: a Ray cluster to attach to; ``None`` reads ``RAY_ADDRESS`` and without it
            starts a local Ray instance for the run.

    A ``KeyboardInterrupt`` saves a checkpoint, writes ``metrics.json`` with
    ``status: interrupted`` and propagates. The run folder is locked while training and its
    ``status.json`` says how the run ended, as the stable-baselines3 path's.

    Raises:
        ConfigError: bad ``train:`` settings (before any work).
        TrainingError: no rllib extra, unreachable cluster, nothing to resume from.
    """
    from flowrun.training.rllib.envs import policy_mapping, probe_agents

    ray = require_ray()
    tc = train_section(cfg)
    seed = train_seed(cfg)
    cfg = replace(cfg, sim=replace(cfg.sim, seed=int(cfg.sim.seed or 0)))
    sections = check_train_config(tc)
    agents = probe_agents(cfg)  # a wrong env.class fails here, before Ray starts
    policies = policy_mapping(cfg, agents, tc.policies) if agents is not None else None
    state = read_state(resume_dir) if resume_dir is not None else None
    # Ray first: an unreachable cluster leaves no run folder behind
    with ray_session(ray_address) as session:
        if resume_dir is not None and state is not None:
            run_dir = resume_dir
            lock = RunLock(run_dir).acquire()
            mark_running(run_dir)
            note_resume(run_dir, cfg, state, argv)
        else:
            run_dir = start_run(out, cfg, seed, argv)
            lock = RunLock(run_dir).acquire()
        try:
            _add_version(run_dir, "ray", str(ray.__version__))
            if policies is not None:
                write_json(run_dir / "policies.json", policies)
            return _train(run_dir, cfg, seed, sections, policies, state, session, progress,
                          should_stop or _never)  # fmt: skip
        finally:
            lock.release()


def _never() -> bool:
    return False


def _train(
    run_dir: Path,
    cfg: ExperimentConfig,
    seed: int,
    sections: dict[str, dict[str, Any]],
    policies: dict[str, str] | None,
    state: dict[str, Any] | None,
    session: RaySession,
    progress: TrainProgress | None,
    should_stop: Callable[[], bool],
) -> TrainResult:
    """Build the algorithm, train, checkpoint; ``metrics.json`` and ``status.json`` whatever
    happens."""
    from tensorboardX import SummaryWriter

    tc = train_section(cfg)
    ckpt_dir = run_dir / "checkpoints"
    ckpt_dir.mkdir(exist_ok=True)
    done = int(state["timesteps"]) if state else 0
    best = state.get("best_return") if state else None
    status, wall, iteration, error, exit_code = "failed", 0.0, 0, "", 1
    algo: Any = None
    try:
        algo = _build_algo(cfg, sections, seed, session, policies, state, ckpt_dir)
        start = time.monotonic()
        writer = SummaryWriter(str(run_dir / "tensorboard"))
        try:
            for result in _iterations(algo, tc, done):
                iteration = int(result["training_iteration"])
                before, done = done, int(result.get("num_env_steps_sampled_lifetime", 0))
                ret = _number(result, "env_runners", "episode_return_mean")
                score = _number(result, "evaluation", "env_runners", "episode_return_mean")
                _log_iteration(run_dir, writer, result, iteration, done, ret, score)
                best = keep_checkpoints(algo, run_dir, tc.checkpoint_freq, iteration,
                                         (before, done), score, best)  # fmt: skip
                if progress is not None:
                    progress(done, tc.total_timesteps, ret)
                if should_stop():
                    status = "interrupted"
                    exit_code = int(getattr(should_stop, "exit_code", 130))
                    save_checkpoint(algo, ckpt_dir, algo.iteration, done, best)
                    break
            else:
                status, exit_code = "complete", 0
                save_tree(algo, run_dir / FINAL_CHECKPOINT)
                save_checkpoint(algo, ckpt_dir, iteration or algo.iteration, done, best)
        except KeyboardInterrupt as err:
            status, exit_code = "interrupted", exit_code_of(err)
            path = save_checkpoint(algo, ckpt_dir, algo.iteration, done, best)
            log.info("interrupted: checkpoint saved to %s", path)
            raise
        except Exception as err:
            error = f"{type(err).__name__}: {err}"
            raise
        finally:
            wall = time.monotonic() - start
            writer.close()
    finally:
        if algo is not None:
            algo.stop()
        _write_metrics(run_dir, cfg, tc, seed, status, done, wall, state, iteration, best,
                       session.address, policies)  # fmt: skip
        mark_done(run_dir, status, error=error or None, exit_code=exit_code)
    resumed = int(state["timesteps"]) if state else 0
    return TrainResult(run_dir, done, wall, status, resumed)


def _build_algo(
    cfg: ExperimentConfig,
    sections: dict[str, dict[str, Any]],
    seed: int,
    session: RaySession,
    policies: dict[str, str] | None,
    state: dict[str, Any] | None,
    ckpt_dir: Path,
) -> Any:
    """RLlib's PPO for the config (evaluating about every ``train.eval_freq`` env steps, in
    whole iterations), restored from the run's latest checkpoint when resuming (``state``)."""
    from flowrun.training.rllib.envs import ENV_NAME, env_config_of, register

    tc = train_section(cfg)
    done = int(state["timesteps"]) if state else 0
    register()
    iter_steps = steps_per_iteration(
        build_ppo_config(sections, ENV_NAME, {}, 0, seed, session.cpus)
    )
    config = build_ppo_config(
        sections, ENV_NAME, env_config_of(cfg), env_runners(tc),
        seed if state is None else seed + done,  # resumed runs see new episodes
        session.cpus,
        env_config_of(cfg, evaluate=True) if tc.eval_freq > 0 else None,
        eval_interval=max(1, round(tc.eval_freq / iter_steps)),
        eval_episodes=tc.eval_episodes,
        policies=policies,
    )  # fmt: skip
    algo = config.build_algo()
    if state is not None:
        algo.restore_from_path(str((ckpt_dir / state["checkpoint"]).resolve()))
    return algo


def _iterations(algo: Any, tc: TrainConfig, done: int) -> Iterator[dict[str, Any]]:
    """``algo.train()`` results until ``total_timesteps`` env steps are sampled."""
    while done < tc.total_timesteps:
        result = algo.train()
        done = int(result.get("num_env_steps_sampled_lifetime", 0))
        yield result


def _number(result: dict[str, Any], *path: str) -> float | None:
    value: Any = result
    for key in path:
        if not isinstance(value, dict) or key not in value:
            return None
        value = value[key]
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


def _flat(result: dict[str, Any], prefix: str = "") -> Iterator[tuple[str, float]]:
    for key, value in result.items():
        path = f"{prefix}{key}"
        if isinstance(value, dict):
            yield from _flat(value, path + "/")
        elif isinstance(value, int | float) and not isinstance(value, bool):
            yield path, float(value)


def _log_iteration(
    run_dir: Path,
    writer: Any,
    result: dict[str, Any],
    iteration: int,
    done: int,
    ret: float | None,
    score: float | None,
) -> None:
    """One TensorBoard step (x = env steps) and one ``progress.jsonl`` line per iteration."""
    for key, value in _flat(result):
        if TB_KEYS.match(key) and math.isfinite(value):
            writer.add_scalar(f"rllib/{key}", value, done)
    writer.flush()
    line = {
        "iteration": iteration,
        "timesteps": done,
        "agent_steps": agent_steps(result),
        "episode_return_mean": ret,
        "episode_len_mean": _number(result, "env_runners", "episode_len_mean"),
        "eval_return_mean": score,
        "time_this_iter_s": round(float(result.get("time_this_iter_s", 0.0)), 3),
    }
    with (run_dir / "progress.jsonl").open("a") as f:
        f.write(json.dumps(line) + "\n")


def agent_steps(result: dict[str, Any]) -> int:
    """Agent steps sampled so far by the trained policies (RLlib's module steps; the env steps
    for a single-agent run; the episode agent's one step per episode left out)."""
    steps = result.get("env_runners", {}).get("num_module_steps_sampled_lifetime", {})
    if not isinstance(steps, dict):
        return 0
    return int(sum(float(v) for k, v in steps.items() if k != EPISODE_AGENT))


def _add_version(run_dir: Path, name: str, value: str) -> None:
    path = run_dir / "versions.json"
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        data = {}
    data[name] = value
    write_json(path, data)


def _write_metrics(
    run_dir: Path,
    cfg: ExperimentConfig,
    tc: TrainConfig,
    seed: int,
    status: str,
    done: int,
    wall: float,
    state: dict[str, Any] | None,
    iteration: int,
    best: float | None,
    address: str,
    policies: dict[str, str] | None,
) -> None:
    resumed = int(state["timesteps"]) if state else None
    write_json(
        run_dir / "metrics.json",
        {
            "status": status,
            "partial": status != "complete",
            "backend": "rllib",
            "config": cfg.name,
            "seed": seed,
            "algorithm": "PPO",
            "num_env_runners": env_runners(tc),
            "ray": address,
            "iterations": iteration,
            "timesteps": done,
            "total_timesteps": tc.total_timesteps,
            "resumed_from": resumed,
            "best_eval_return": best,
            "policies": sorted(set(policies.values())) if policies else ["default_policy"],
            "wall_clock_s": round(wall, 3),
            "steps_per_s": round((done - (resumed or 0)) / wall, 1) if wall > 0 else None,
        },
    )
