"""``evaluate_rllib``: roll an RLlib checkpoint out beside its baseline, to MCAP.

The policies are read from the checkpoint's RL modules (no Ray instance is started): the
module's inference output, its action distribution's mode (``deterministic``) or a sample,
and RLlib's action unsquashing to the action space (RLlib's default ``normalize_actions``).
Episodes run through :class:`~flowrun.experiment.runner.Experiment` as the SB3 evaluation's
do, so ``<run>/eval/<timestamp>/`` holds the same ``metrics.json``, ``policy_<i>.mcap`` and
``baseline_<i>.mcap``. A multi-agent episode's return is the sum over steps of the mean
reward of the agents rewarded at that step (the shared reward, for Flow's shared rewards).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.errors import ConfigError, TrainingError
from flowrun.rundir.train_state import run_state
from flowrun.training.evaluate import (
    EvalProgress,
    EvalResult,
    StopAsked,
    eval_config,
    run_evaluation,
)
from flowrun.training.rllib.checkpoints import BEST_CHECKPOINT, FINAL_CHECKPOINT
from flowrun.training.rllib.deps import require_ray
from flowrun.training.trainer import train_section

#: Where an RLlib (new API stack) checkpoint keeps its RL modules.
MODULES_SUBDIR = ("learner_group", "learner", "rl_module")


def checkpoint_path(run_dir: Path, which: str = "best") -> Path:
    """``best`` (falls back to ``final``), ``final``, or a checkpoint folder (e.g.
    ``checkpoints/iter_000002``, relative to the run folder or absolute).

    Raises:
        TrainingError: the checkpoint does not exist.
    """
    if which in ("best", "final"):
        order = (BEST_CHECKPOINT, FINAL_CHECKPOINT) if which == "best" else (FINAL_CHECKPOINT,)
        for name in order:
            if (run_dir / name).is_dir():
                return run_dir / name
        raise TrainingError(
            f"{run_dir} has no {' or '.join(order)}; train first, resume an interrupted run, "
            "or pass --model checkpoints/iter_<n>"
        )
    path = Path(which) if Path(which).is_absolute() else run_dir / which
    if not path.joinpath(*MODULES_SUBDIR).is_dir():
        raise TrainingError(
            f"--model must be best, final or an RLlib checkpoint folder; {path} is none"
        )
    return path


class ModulePolicy:
    """One RLlib RL module as a function from an observation to an action.

    Args:
        module: the RL module (torch).
        deterministic: the distribution's mode instead of a sample.
    """

    def __init__(self, module: Any, deterministic: bool) -> None:
        self.module = module
        self.deterministic = deterministic
        self.dist_cls = module.get_inference_action_dist_cls()
        self.space = module.action_space

    def __call__(self, obs: Any) -> Any:
        """The action for one observation."""
        import torch
        from gymnasium.spaces import Box
        from ray.rllib.utils.spaces.space_utils import unsquash_action

        batch = torch.from_numpy(np.asarray(obs, dtype=np.float32)[None, ...])
        with torch.no_grad():
            out = self.module.forward_inference({"obs": batch})
            dist = self.dist_cls.from_logits(out["action_dist_inputs"])
            if self.deterministic:
                dist = dist.to_deterministic()
            action = dist.sample()[0].numpy()
        if isinstance(self.space, Box):
            return np.asarray(unsquash_action(action, self.space), dtype=np.float32)
        return action


def load_policies(checkpoint: Path, deterministic: bool = True) -> dict[str, ModulePolicy]:
    """Every policy (module id -> :class:`ModulePolicy`) of an RLlib checkpoint."""
    require_ray()
    from ray.rllib.core.rl_module.rl_module import RLModule

    root = checkpoint.joinpath(*MODULES_SUBDIR).resolve()
    multi: Any = RLModule.from_checkpoint(str(root))  # a MultiRLModule: module id -> module
    return {str(mid): ModulePolicy(multi[mid], deterministic) for mid in list(multi.keys())}


def evaluate_rllib(
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
    """Roll out the RLlib policy and its baseline, ``episodes`` each (as
    :func:`flowrun.training.evaluate`).

    Episode ``i`` of both resets with seed ``sim.seed + i``. Writes ``metrics.json`` (``status``
    ``running``, then ``complete`` or ``interrupted``) and the MCAP logs (``policy_<i>.mcap``,
    ``baseline_<i>.mcap``) to ``<out>/<timestamp>-<seed>/``, ``out`` defaulting to
    ``<run>/eval``.

    Args:
        run_dir: the train run folder.
        episodes: episodes of each rollout.
        deterministic: the policy's mode instead of sampled actions.
        overrides: ``--set`` overrides of the run's config.
        config_override: a YAML whose sections override the run's config.
        model: ``best``, ``final`` or a checkpoint folder (see :func:`checkpoint_path`).
        progress: called as ``progress(label, episode, step)``.
        out: parent of the evaluation folder (``None``: ``<run>/eval``).
        should_stop: whether a stop signal came (see :func:`run_evaluation`).

    Raises:
        ConfigError: ``episodes`` < 1 or a bad override.
        TrainingError: no such checkpoint, or no rllib extra.
    """
    if episodes < 1:
        raise ConfigError(f"--episodes must be >= 1, got {episodes}")
    cfg = eval_config(run_dir, overrides, config_override)
    tc = train_section(cfg)
    path = checkpoint_path(run_dir, model)
    policies = load_policies(path, deterministic)
    act = _actor(cfg, run_dir, tc.policies, policies)

    head = {"deterministic": deterministic, "backend": "rllib"}
    return run_evaluation(cfg, run_dir, path, run_state(run_dir), head, act, episodes,
                          progress, out, should_stop=should_stop)  # fmt: skip


def _actor(
    cfg: ExperimentConfig, run_dir: Path, mode: str, policies: dict[str, ModulePolicy]
) -> Callable[[Any], Any]:
    """``obs -> action`` for a single-agent run, ``{agent: obs} -> {agent: action}`` else."""
    mapping_file = run_dir / "policies.json"
    if not mapping_file.is_file():
        policy = policies.get("default_policy") or next(iter(policies.values()))
        return policy
    saved: dict[str, str] = json.loads(mapping_file.read_text())
    fallback = mode == "shared" and "shared" in policies

    def act(obs: dict[str, Any]) -> dict[str, Any]:
        actions = {}
        for agent, o in obs.items():
            module = saved.get(agent, "shared" if fallback else "")
            if module not in policies:
                raise TrainingError(
                    f"agent {agent} has no policy in the checkpoint (policies: "
                    f"{', '.join(sorted(policies))}); evaluate with the training config's agents"
                )
            actions[agent] = policies[module](o)
        return actions

    return act
