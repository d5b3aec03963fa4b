"""``flowrun validate``: everything ``baseline`` and ``train`` check before they start, located.

:func:`load_config` checks the file, each value and what spans sections. Before a run,
``baseline`` and ``train`` also resolve the environment class (importing a user's
``module:Class``), check its ``ADDITIONAL_ENV_PARAMS`` and, for training, the
hyper-parameter names against stable-baselines3's signatures. :func:`validate_config` runs
those too, and reports each problem at the ``file:line`` of the key to change.

Importing happens: an import path in ``env.class`` or in a controller's ``type`` runs that
module's top-level code, exactly as ``baseline``/``train`` would; validate only what you would
run.
"""

from __future__ import annotations

import importlib.util
import inspect
import logging
import os
from collections.abc import Sequence
from typing import Any

from flowrun.config.model import ExperimentConfig
from flowrun.config.params import is_rl
from flowrun.config.yamlio import Locations
from flowrun.envs.factory import env_class, make_network
from flowrun.errors import ConfigError, TrainingError
from flowrun.loading.experiment_checks import check_env_params, sub_path
from flowrun.loading.flow_module import is_flow_module, load_any_config
from flowrun.loading.loader import load_config_located
from flowrun.preflight.installed import training_library_problem
from flowrun.suggest import did_you_mean

log = logging.getLogger(__name__)

#: Built-in environments whose actions drive RL vehicles (training needs at least one).
RL_VEHICLE_ENVS = ("AccelEnv", "LaneChangeAccelEnv", "WaveAttenuationEnv",
                   "WaveAttenuationPOEnv", "MergePOEnv", "MultiAgentAccelPOEnv",
                   "MultiAgentWaveAttenuationPOEnv", "MultiAgentMergePOEnv",
                   "MultiAgentHighwayPOEnv")  # fmt: skip


def validate_config(
    path: str | os.PathLike[str], overrides: Sequence[str] = ()
) -> ExperimentConfig:
    """Load a YAML config (or Flow config module) and run every check a run would.

    A ``train:`` section whose library is not installed is a warning, not an error: the
    config is valid (``baseline`` runs it), ``train`` refuses it saying how to install it.

    Raises:
        ConfigError: the first problem, at its ``file:line`` and key path.
    """
    if is_flow_module(path):
        cfg = load_any_config(path, overrides)
        locations = Locations(str(path))
    else:
        cfg, locations = load_config_located(path, overrides)
    preflight(cfg, locations)
    missing = training_library_problem(cfg, locations)
    if missing is not None:
        log.warning("%s; the config is valid (baseline runs it), only train needs it", missing)
    return cfg


def preflight(cfg: ExperimentConfig, loc: Locations) -> None:
    """The checks ``baseline``/``train`` make before creating a run folder (see module doc).

    Raises:
        ConfigError: located with ``loc``.
    """
    cls = _env_class(cfg, loc)
    if cls is not None:
        declared = dict(getattr(cls, "ADDITIONAL_ENV_PARAMS", {}) or {})
        check_env_params(cfg.env.additional_params, declared, loc)
        _check_env_network(cfg, cls, loc)
    if cfg.train is not None:
        _check_rl_vehicles(cfg, cls, loc)
        _check_hyperparam_names(cfg, loc)
        _check_rllib(cfg, loc)
        _check_numpy_backends(cfg, loc)
        _check_ars_only(cfg, loc)


def _check_ars_only(cfg: ExperimentConfig, loc: Locations) -> None:
    """``train.common_random_numbers`` is an ARS setting: refused with another algorithm."""
    tc = cfg.train
    if tc is not None and tc.common_random_numbers and (
        tc.algorithm != "ARS" or tc.backend != "sb3"
    ):
        raise loc.error(
            f"common_random_numbers is an ARS setting (candidates that share their episodes), "
            f"not one of {tc.algorithm} on {tc.backend}; remove it or use algorithm: ARS",
            ("train", "common_random_numbers"),
        )


def _check_numpy_backends(cfg: ExperimentConfig, loc: Locations) -> None:
    """``sim.backend: numpy`` and ``train.eval_backend: numpy`` on a config the numpy rings
    cannot run (what ``train`` checks before it starts)."""
    from flowrun.fastring.plan import check_numpy_backend  # only when a config trains

    try:
        check_numpy_backend(cfg)
        if cfg.train is not None and cfg.train.eval_backend == "numpy" and cfg.train.eval_freq > 0:
            from flowrun.training.numpy_eval import numpy_eval_plan

            numpy_eval_plan(cfg)
    except ConfigError as err:
        raise _relocated(err, loc) from None


def _check_rllib(cfg: ExperimentConfig, loc: Locations) -> None:
    """The RLlib backend's own check of ``train:`` (what ``train`` runs before it starts)."""
    if cfg.train is None or cfg.train.backend != "rllib":
        return
    from flowrun.training.rllib.options import check_train_config

    try:
        check_train_config(cfg.train)
    except ConfigError as err:
        raise _relocated(err, loc) from None
    except (TrainingError, ModuleNotFoundError):
        return  # Ray is not installed: train says how to install it


def _relocated(err: ConfigError, loc: Locations) -> ConfigError:
    return loc.error(err.message, sub_path(err.path)) if err.path else err


def _env_class(cfg: ExperimentConfig, loc: Locations) -> Any:
    try:
        return env_class(cfg)
    except ConfigError as err:
        raise _relocated(err, loc) from None


def _check_env_network(cfg: ExperimentConfig, cls: Any, loc: Locations) -> None:
    """The env class's own check of its network (``check_network``, e.g. a signal env on a
    network without lights), where it has one; builds the network object, starts nothing."""
    check = getattr(cls, "check_network", None)
    if check is None:
        return
    try:
        check(make_network(cfg))
    except ConfigError as err:
        raise _relocated(err, loc) from None


def _check_rl_vehicles(cfg: ExperimentConfig, cls: Any, loc: Locations) -> None:
    name = getattr(cls, "__name__", cfg.env.env_class or "AccelEnv")
    builtin = getattr(cls, "__module__", "flowrun").startswith("flowrun")
    if name not in RL_VEHICLE_ENVS or not builtin:
        return
    rl_groups = [g.veh_id for g in cfg.vehicles.groups if is_rl(g)]
    inflows = cfg.network.net_params.inflows
    rl_inflows = [f for f in (inflows.get() if inflows else []) if f.veh_type in rl_groups]
    if cfg.vehicles.num_rl_vehicles == 0 and not rl_inflows:
        at = ("env", "class") if cfg.env.env_class else ("train",)
        raise loc.error(
            f"{name} trains RL vehicles, but no vehicle group with "
            "acceleration_controller RLController has a count > 0 (or an inflow); add one "
            "(see configs/ring_wave.yaml) or use flowrun baseline",
            at,
        )


def _check_hyperparam_names(cfg: ExperimentConfig, loc: Locations) -> None:
    train = cfg.train
    if train is None or train.backend != "sb3" or not train.hyperparams:
        return
    if importlib.util.find_spec("stable_baselines3") is None:
        return  # train refuses to start without the extra anyway, saying how to install it
    from flowrun.training.algorithms import build_hyperparams

    try:
        build_hyperparams(train.algorithm, train.hyperparams)
    except ConfigError as err:
        raise _relocated(err, loc) from None
    except TrainingError:
        return  # the algorithm's package (sb3-contrib) is missing: train says how to install it
    _check_policy(cfg, loc)


def _check_policy(cfg: ExperimentConfig, loc: Locations) -> None:
    """``train.policy`` is one of the algorithm's policy names; ``policy_kwargs`` are
    arguments of that policy class (SB3 would fail with a TypeError after the envs started)."""
    train = cfg.train
    from flowrun.training.algorithms import algorithm_class

    if train is None:
        return
    try:
        algo = algorithm_class(train.algorithm)
    except (ConfigError, TrainingError):
        return
    policies: dict[str, Any] = dict(getattr(algo, "policy_aliases", {}) or {})
    if train.policy not in policies:
        raise loc.error(
            f"{train.algorithm} has no policy '{train.policy}'"
            f"{did_you_mean(train.policy, policies)}; expected one of: {', '.join(policies)}",
            ("train", "policy"),
        )
    params = inspect.signature(policies[train.policy].__init__).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return
    fixed = ("self", "observation_space", "action_space", "lr_schedule")
    accepted = [name for name in params if name not in fixed]
    for key in train.policy_kwargs:
        if key not in accepted:
            raise loc.error(
                f"{train.policy} takes no argument '{key}'{did_you_mean(str(key), accepted)}; "
                f"expected one of: {', '.join(accepted)}",
                ("train", "policy_kwargs", key),
            )
