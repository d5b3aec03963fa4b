"""Value rules of ``train.hyperparams`` (stable-baselines3's names), checked without SB3.

Run when a config is loaded (:mod:`flowrun.loading.experiment_checks`), so ``batch_size: 0``
or ``gamma: 2`` is refused at its line instead of failing in training. The names themselves
are checked against SB3's signatures when training starts
(:func:`flowrun.training.algorithms.build_hyperparams`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from flowrun.config.schedules import SCHEDULE_PARAMS, parse_schedule
from flowrun.errors import ConfigError

# Value rules of SB3's hyper-parameters (its names), checked when the config is loaded, so
# ``batch_size: 0`` or ``gamma: 2`` is refused with its line instead of failing in training.
# name -> (kind, low, high, low open): kind "int" or "float"; ``None`` bounds are open ends.
_RULES: dict[str, tuple[str, float | None, float | None, bool]] = {
    "n_steps": ("int", 1, None, False),
    "batch_size": ("int", 1, None, False),
    "n_epochs": ("int", 1, None, False),
    "buffer_size": ("int", 1, None, False),
    "learning_starts": ("int", 0, None, False),
    "gradient_steps": ("int", -1, None, False),
    "policy_delay": ("int", 1, None, False),
    "target_update_interval": ("int", 1, None, False),
    "sde_sample_freq": ("int", -1, None, False),
    "stats_window_size": ("int", 1, None, False),
    "cg_max_steps": ("int", 1, None, False),
    "line_search_max_iter": ("int", 1, None, False),
    "n_critic_updates": ("int", 1, None, False),
    "sub_sampling_factor": ("int", 1, None, False),
    "n_delta": ("int", 1, None, False),
    "n_top": ("int", 1, None, False),
    "n_eval_episodes": ("int", 1, None, False),
    "delta_std": ("float", 0, None, True),
    "gamma": ("float", 0, 1, False),
    "gae_lambda": ("float", 0, 1, False),
    "tau": ("float", 0, 1, False),
    "vf_coef": ("float", 0, None, False),
    "max_grad_norm": ("float", 0, None, True),
    "target_kl": ("float", 0, None, True),
    "rms_prop_eps": ("float", 0, None, True),
    "target_policy_noise": ("float", 0, None, False),
    "target_noise_clip": ("float", 0, None, False),
    "cg_damping": ("float", 0, None, False),
    "line_search_shrinking_factor": ("float", 0, 1, True),
    "learning_rate": ("float", 0, None, True),
    "clip_range": ("float", 0, None, True),
    "clip_range_vf": ("float", 0, None, True),
    "ent_coef": ("float", 0, None, False),
}
_BOOLS = ("normalize_advantage", "use_sde", "use_rms_prop", "sde_support",
          "optimize_memory_usage", "share_features_extractor", "zero_policy")  # fmt: skip
# SAC's ``ent_coef: auto`` / ``auto_0.1`` and ``target_entropy: auto`` are strings.
_AUTO = ("ent_coef", "target_entropy")


def check_hyperparam_values(
    algorithm: str, hyperparams: Mapping[str, Any], n_envs: int = 1
) -> None:
    """Refuse values SB3 would fail on (or train nonsense with), without importing SB3.

    Numbers must be finite everywhere (schedules too); known names must be in range
    (``batch_size >= 1``, ``0 <= gamma <= 1``, ...); PPO needs ``batch_size > 1`` and
    ``n_steps * n_envs > 1``. Names are checked against SB3's signatures by
    :func:`build_hyperparams`.

    Raises:
        ConfigError: with path ``train.hyperparams.<name>``.
    """
    for name, value in hyperparams.items():
        path = f"train.hyperparams.{name}"
        _check_finite(value, path)
        if value is None:
            continue
        if name in _AUTO and isinstance(value, str):
            if not value.startswith("auto"):
                raise ConfigError(f"expected a number or 'auto', got {value!r}", path)
            continue
        if name in _BOOLS and not isinstance(value, bool):
            raise ConfigError(f"expected true or false, got {value!r}", path)
        if name in _RULES:
            _check_rule(name, value, path)
        if name == "train_freq" and not isinstance(value, list):
            _check_rule("n_epochs", value, path)  # an integer >= 1
    if algorithm in ("PPO", "TRPO"):
        n_steps = hyperparams.get("n_steps", 2048)
        if isinstance(n_steps, int) and n_steps * n_envs <= 1:
            raise ConfigError(
                f"{algorithm} needs n_steps * n_envs > 1 (got {n_steps} x {n_envs}): its "
                "advantage estimate needs more than one step per update",
                "train.hyperparams.n_steps",
            )
    _check_ars(algorithm, hyperparams)
    batch = hyperparams.get("batch_size")
    if algorithm == "PPO" and isinstance(batch, int) and batch == 1:
        raise ConfigError(
            "PPO needs batch_size > 1 (a mini-batch of one cannot normalise advantages)",
            "train.hyperparams.batch_size",
        )


def _check_ars(algorithm: str, hyperparams: Mapping[str, Any]) -> None:
    """ARS keeps the ``n_top`` best of its ``n_delta`` directions: ``n_top <= n_delta``."""
    if algorithm != "ARS":
        return
    n_delta, n_top = hyperparams.get("n_delta", 8), hyperparams.get("n_top")
    if isinstance(n_top, int) and isinstance(n_delta, int) and n_top > n_delta:
        raise ConfigError(
            f"ARS keeps the n_top best of its n_delta directions: n_top ({n_top}) must be "
            f"<= n_delta ({n_delta})",
            "train.hyperparams.n_top",
        )


def _check_finite(value: Any, path: str) -> None:
    if isinstance(value, float) and not math.isfinite(value):
        raise ConfigError(f"must be a finite number, got {value!r}", path)
    if isinstance(value, Mapping):
        for key, item in value.items():
            _check_finite(item, f"{path}.{key}")
    elif isinstance(value, list):
        for i, item in enumerate(value):
            _check_finite(item, f"{path}[{i}]")


def _check_rule(name: str, value: Any, path: str, decays_to: bool = False) -> None:
    kind, low, high, low_open = _RULES[name]
    low_open = low_open and not decays_to  # a schedule may decay to 0
    if name in SCHEDULE_PARAMS and isinstance(value, Mapping):
        parse_schedule(value, path)  # its shape; then each number of it
        for arg in value.values():
            for i, x in enumerate(arg if isinstance(arg, list) else [arg]):
                _check_rule(name, x, path, decays_to=i > 0)
        return
    numeric = int if kind == "int" else (int, float)
    if isinstance(value, bool) or not isinstance(value, numeric):
        what = "an integer" if kind == "int" else "a number"
        raise ConfigError(f"expected {what}, got {value!r}", path)
    too_low = low is not None and (value <= low if low_open else value < low)
    too_high = high is not None and value > high
    if too_low or too_high:
        lo = "" if low is None else f"{'>' if low_open else '>='} {low:g}"
        hi = "" if high is None else f"<= {high:g}"
        wanted = " and ".join(x for x in (lo, hi) if x)
        raise ConfigError(f"must be {wanted}, got {value!r}", path)
