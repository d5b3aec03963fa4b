"""Everything ``flowrun train`` checks before it starts, in one place.

:func:`prepare_training` loads the config (or the run folder's, for ``--resume``), runs the
pre-flight checks (:func:`flowrun.preflight.checks.preflight`, at ``file:line``), checks the
training library is installed and that the options fit the backend, and returns what to train
with the notes to tell the user. Nothing is written; usable without the command line.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from flowrun.config.model import ExperimentConfig, TrainConfig
from flowrun.config.yamlio import Locations
from flowrun.errors import FlowrunError
from flowrun.loading.flow_module import is_flow_module, load_any_config
from flowrun.loading.loader import load_config, load_config_located
from flowrun.preflight.checks import preflight
from flowrun.preflight.installed import check_training_installed
from flowrun.rundir.train_state import read_metrics, run_state


@dataclass(frozen=True)
class TrainPlan:
    """What ``flowrun train`` trains.

    Attributes:
        cfg: the experiment, with its ``train:`` section.
        rllib: whether it trains with RLlib (``train.backend: rllib``) rather than SB3.
        notes: what the user should be told before training starts.
    """

    cfg: ExperimentConfig
    rllib: bool
    notes: list[str] = field(default_factory=list)

    @property
    def train(self) -> TrainConfig:
        """The ``train:`` section."""
        return self.cfg.train or TrainConfig()


def prepare_training(
    config: Path,
    overrides: list[str],
    resume: Path | None = None,
    out_given: bool = False,
    ray_address: str | None = None,
) -> TrainPlan:
    """The checked training plan for ``config`` (or, with ``resume``, that run folder).

    Args:
        config: a YAML config or a Flow config module (not read with ``resume``).
        overrides: ``--set`` values (and ``--seed`` as ``sim.seed``/``train.seed``).
        resume: a run folder to continue.
        out_given: whether ``--out`` was given (it has no effect with ``resume``).
        ray_address: ``--ray-address`` (for RLlib only).

    Raises:
        ConfigError: a config problem (a training library that is not installed too), at
            ``file:line``.
        FlowrunError: a run folder that cannot be resumed, an option that does not fit the
            backend.
    """
    notes: list[str] = []
    if resume is not None:
        cfg = _resumed_config(resume, overrides, out_given)
        where = Locations(str(resume / "config.yaml"))
        notes.append(f"resuming {resume} with its config.yaml (CONFIG is not re-read)")
    else:
        if is_flow_module(config):
            cfg, where = load_any_config(config, overrides), Locations(str(config))
        else:
            cfg, where = load_config_located(config, overrides)
        if cfg.train is None and is_flow_module(config):
            cfg = replace(cfg, train=TrainConfig())
            notes.append(
                "a Flow config has no train: section: training PPO with flowrun's defaults "
                "(change them with --set train.total_timesteps=... etc.)"
            )
        preflight(cfg, where)  # env class, its params, hyper-parameter names: at file:line
    rllib = cfg.train is not None and cfg.train.backend == "rllib"
    check_training_installed(cfg, where)  # at train.algorithm's file:line, before any process
    _check_ray_address(rllib, ray_address)
    return TrainPlan(cfg, rllib, notes)


def check_recipe(config: Path, overrides: list[str]) -> ExperimentConfig:
    """What ``train`` checks of a YAML config before it starts (``flowrun benchmark --train``
    asks it of every benchmark before anything runs).

    Raises:
        ConfigError: a config problem or a training library that is not installed, at
            ``file:line``.
    """
    cfg, where = load_config_located(config, overrides)
    preflight(cfg, where)
    check_training_installed(cfg, where)
    return cfg


def not_a_training_run(run_dir: Path) -> FlowrunError:
    """The error for a run folder whose config has no ``train:`` section (a baseline run)."""
    return FlowrunError(
        f"{run_dir} is not a training run: its config.yaml has no train: section (a "
        "baseline run folder?); pass a folder made by flowrun train"
    )


def _resumed_config(resume: Path, overrides: list[str], out_given: bool) -> ExperimentConfig:
    from flowrun.training.resume import resume_config

    if out_given:
        raise FlowrunError(
            f"--out has no effect with --resume: training continues in {resume}; drop --out"
        )
    saved = resume / "config.yaml"
    if saved.is_file() and load_config(saved).train is None:
        raise not_a_training_run(resume)
    cfg = resume_config(resume, overrides)
    _check_steps_left(resume, cfg.train.total_timesteps if cfg.train else 0)
    return cfg


def _check_steps_left(run_dir: Path, total: int) -> None:
    """Refuse to resume a complete run that has already trained ``total`` steps (it would
    train nothing and replace its final model and evaluation)."""
    done = (read_metrics(run_dir) or {}).get("timesteps")
    if run_state(run_dir) == "complete" and isinstance(done, int) and done >= total:
        raise FlowrunError(
            f"{run_dir} already trained {done} of train.total_timesteps={total} steps; to "
            f"continue, raise it (--set train.total_timesteps={2 * done}), or evaluate it "
            f"with flowrun eval {run_dir}"
        )


def _check_ray_address(rllib: bool, ray_address: str | None) -> None:
    """``--ray-address`` only with RLlib."""
    if ray_address is not None and not rllib:
        raise FlowrunError(
            "--ray-address is for train.backend: rllib; this config trains with "
            "stable-baselines3 (set train.backend: rllib, or drop --ray-address)"
        )
