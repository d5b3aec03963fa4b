"""The ``train:`` section for RLlib: checked, then turned into an RLlib ``PPOConfig``.

``train.rllib`` holds PPO settings under RLlib's own names: every parameter of
``PPOConfig.training``, ``.env_runners``, ``.learners``, ``.rl_module`` and ``.reporting``
(RLlib 2.60: ``lr``, ``gamma``, ``lambda_`` (``lambda`` is accepted), ``clip_param``,
``entropy_coeff``, ``vf_loss_coeff``, ``grad_clip``, ``train_batch_size_per_learner``,
``minibatch_size``, ``num_epochs``, ``rollout_fragment_length``, ``num_learners``,
``model_config: {fcnet_hiddens: [64, 64]}``, ...). A name flowrun sets from another field, a
deprecated name, or one that takes Python objects is refused with the field to use instead;
an unknown name gets a did-you-mean.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping
from functools import cache
from typing import Any

from flowrun.config.model import TrainConfig
from flowrun.errors import ConfigError
from flowrun.suggest import did_you_mean, unknown_name

#: ``PPOConfig`` methods whose parameters ``train.rllib`` may set.
SECTIONS = ("training", "env_runners", "learners", "rl_module", "reporting")
#: Flow's / RLlib's old spellings -> the current parameter.
ALIASES = {"lambda": "lambda_"}
#: RLlib names flowrun sets itself, and the ``train:`` field that sets them.
MANAGED = {
    "num_env_runners": "train.num_env_runners",
    "num_rollout_workers": "train.num_env_runners",
    "seed": "train.seed",
    "policies": "train.policies",
    "policy_mapping_fn": "train.policies",
    "evaluation_interval": "train.eval_freq",
    "evaluation_duration": "train.eval_episodes",
    "env": "env.class",
    "env_config": "the config's sections",
}
#: Parameters that are deprecated, need Python objects, or break flowrun's assumptions.
EXCLUDED = frozenset({
    "kwargs", "model", "num_sgd_iter", "num_envs_per_worker", "env_runner_cls",
    "create_local_env_runner", "create_env_on_local_worker", "env_to_module_connector",
    "module_to_env_connector", "learner_class", "learner_connector", "rl_module_spec",
    "custom_stats_cls_lookup", "exploration_config", "sample_collector", "remote_worker_envs",
    "remote_env_batch_wait_ms", "preprocessor_pref", "observation_filter",
    "enable_tf1_exec_eagerly", "validate_workers_after_construction", "ignore_worker_failures",
    "recreate_failed_workers", "num_consecutive_worker_failures_tolerance",
    "worker_health_probe_timeout_s", "worker_restore_timeout_s", "synchronize_filter",
    "enable_connectors", "_enable_rl_module_api", "model_config_dict", "entropy_coeff_schedule",
    "lr_schedule", "max_requests_in_flight_per_sampler_worker", "episode_lookback_horizon",
    "explore", "gym_env_vectorize_mode", "add_default_connectors_to_env_to_module_pipeline",
    "add_default_connectors_to_module_to_env_pipeline",
    "add_default_connectors_to_learner_pipeline", "algorithm_config_overrides_per_module",
})  # fmt: skip
#: How the agents of a multi-agent env map to policies (``train.policies``).
POLICY_MODES = ("shared", "group", "agent")
#: The agent (and its module, never trained) that keeps RLlib's multi-agent episode as long as
#: the env's: see :class:`flowrun.training.rllib.envs.RLlibMultiAgentEnv`.
EPISODE_AGENT = "__episode__"


@cache
def allowed_options() -> dict[str, str]:
    """Every name ``train.rllib`` accepts -> the ``PPOConfig`` method that takes it."""
    from ray.rllib.algorithms.algorithm_config import AlgorithmConfig
    from ray.rllib.algorithms.ppo import PPOConfig

    names: dict[str, str] = {}
    for section in SECTIONS:
        # PPOConfig.training passes **kwargs on to AlgorithmConfig.training
        for cls in (PPOConfig, AlgorithmConfig):
            for name in inspect.signature(getattr(cls, section)).parameters:
                if name != "self" and name not in EXCLUDED and name not in MANAGED:
                    names.setdefault(name, section)
    return names


def _check_type(name: str, value: Any, default: Any) -> str | None:
    """What is wrong with ``value`` given RLlib's default ``default`` (``None``: nothing)."""
    if isinstance(default, bool):
        return None if isinstance(value, bool) else "expected true or false"
    if isinstance(default, int | float) and default is not None:
        if isinstance(value, bool) or not isinstance(value, int | float):
            return "expected a number"
        if isinstance(default, int) and not isinstance(value, int) and name != "grad_clip":
            return "expected a whole number"
        if isinstance(value, float) and not math.isfinite(value):
            return "expected a finite number"
    return None


def check_options(options: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """``train.rllib`` split by ``PPOConfig`` method, names and value types checked.

    Raises:
        ConfigError: an unknown, managed or excluded name (with what to use instead), or a
            value of the wrong type, with its key path ``train.rllib.<name>``.
    """
    from ray.rllib.algorithms.ppo import PPOConfig

    allowed = allowed_options()
    defaults = PPOConfig()
    out: dict[str, dict[str, Any]] = {s: {} for s in SECTIONS}
    for given, value in options.items():
        name = ALIASES.get(given, given)
        path = f"train.rllib.{given}"
        if name in MANAGED:
            raise ConfigError(f"flowrun sets '{name}' from {MANAGED[name]}; set that instead", path)
        if name in EXCLUDED:
            raise ConfigError(f"'{name}' cannot be set from a config with flowrun", path)
        section = allowed.get(name)
        if section is None:
            hint = did_you_mean(name, [*allowed, *ALIASES])
            raise ConfigError(
                f"unknown RLlib PPO option '{given}'{hint}; RLlib's names of PPOConfig."
                f"{'/'.join(SECTIONS)} parameters are accepted",
                path,
            )
        problem = _check_type(name, value, getattr(defaults, name, None))
        if problem:
            raise ConfigError(f"{problem}, got {value!r}", path)
        out[section][name] = value
    if out["env_runners"].get("num_envs_per_env_runner", 1) != 1:
        raise ConfigError(
            "must be 1: libsumo runs one simulation per process; use train.num_env_runners "
            "for more environments",
            "train.rllib.num_envs_per_env_runner",
        )
    return out


def env_runners(tc: TrainConfig) -> int:
    """Env runners of the run: ``train.num_env_runners``, else ``train.n_envs``."""
    return int(tc.n_envs if tc.num_env_runners is None else tc.num_env_runners)


def check_train_config(tc: TrainConfig) -> dict[str, dict[str, Any]]:
    """Check the ``train:`` fields the RLlib backend reads; return :func:`check_options`'s split.

    Raises:
        ConfigError: with the key path of the first problem.
    """
    if tc.algorithm.upper() != "PPO":
        raise ConfigError(
            f"the rllib backend trains PPO only, got '{tc.algorithm}'", "train.algorithm"
        )
    if tc.num_env_runners is not None and (
        isinstance(tc.num_env_runners, bool) or tc.num_env_runners < 0
    ):
        raise ConfigError(
            f"expected a whole number >= 0, got {tc.num_env_runners!r}", "train.num_env_runners"
        )
    if tc.policies not in POLICY_MODES:
        raise ConfigError(
            unknown_name("policies", tc.policies, POLICY_MODES, sort=False), "train.policies"
        )
    if tc.hyperparams:
        raise ConfigError(
            "holds stable-baselines3 names; with backend: rllib put PPO settings under "
            "train.rllib, by RLlib's names (lr, gamma, train_batch_size_per_learner, ...)",
            "train.hyperparams",
        )
    if tc.policy_kwargs:
        raise ConfigError(
            "holds stable-baselines3 policy arguments; with backend: rllib set the network "
            "as train.rllib.model_config (e.g. {fcnet_hiddens: [64, 64]})",
            "train.policy_kwargs",
        )
    if tc.normalize:
        raise ConfigError(
            "VecNormalize is stable-baselines3's; the rllib backend trains on the raw "
            "observations and rewards: set it false",
            "train.normalize",
        )
    return check_options(tc.rllib)


def cpus_per_runner(options: Mapping[str, Any], actors: int, cpus: float) -> float:
    """CPUs each env runner reserves: the user's ``num_cpus_per_env_runner``, else 1, shrunk so
    all ``actors`` fit on ``cpus`` logical CPUs (Ray would otherwise wait for CPUs forever)."""
    given = options.get("num_cpus_per_env_runner")
    if given is not None:
        return float(given)
    if actors <= 0:
        return 1.0
    return max(0.01, min(1.0, math.floor(100 * cpus / actors) / 100))


def build_ppo_config(
    sections: Mapping[str, Mapping[str, Any]],
    env_name: str,
    env_config: dict[str, Any],
    runners: int,
    seed: int,
    cpus: float,
    eval_env_config: dict[str, Any] | None = None,
    eval_interval: int = 1,
    eval_episodes: int = 1,
    policies: Mapping[str, str] | None = None,
) -> Any:
    """An RLlib ``PPOConfig`` (new API stack, torch) for one flowrun run.

    Args:
        sections: :func:`check_options`'s output.
        env_name: the name the env creator is registered under.
        env_config: passed to the env creator of the training env runners.
        runners: env runners (0 samples in the driver).
        seed: RLlib's seed (env runners derive their env seeds from it).
        cpus: logical CPUs of the Ray cluster (sizes the env runners, see
            :func:`cpus_per_runner`).
        eval_env_config: the evaluation env's config; ``None``: no evaluation while training.
        eval_interval: evaluate every this many iterations.
        eval_episodes: episodes per evaluation.
        policies: multi-agent only: agent id -> policy (module) id.

    Raises:
        ConfigError: RLlib rejects the combination of settings.
    """
    from ray.rllib.algorithms.ppo import PPOConfig

    actors = runners + (1 if eval_env_config is not None else 0)
    runner_opts = dict(sections.get("env_runners", {}))
    runner_opts["num_cpus_per_env_runner"] = cpus_per_runner(runner_opts, actors, cpus)
    config = (
        PPOConfig()
        .framework("torch")
        .environment(env_name, env_config=env_config)
        .env_runners(num_env_runners=runners, **runner_opts)
        .debugging(seed=seed, log_level="WARN")
    )
    for section in ("training", "learners", "rl_module", "reporting"):
        opts = sections.get(section)
        if opts:
            getattr(config, section)(**opts)
    if eval_env_config is not None:
        config.evaluation(
            evaluation_interval=max(1, eval_interval),
            evaluation_duration=eval_episodes,
            evaluation_duration_unit="episodes",
            evaluation_num_env_runners=1,  # never a second SUMO in the driver
            evaluation_config={"env_config": eval_env_config, "explore": False},
        )
    if policies is not None:
        from functools import partial

        trained = set(policies.values())
        config.multi_agent(
            policies=trained | {EPISODE_AGENT},
            policy_mapping_fn=partial(map_agent, {**policies, EPISODE_AGENT: EPISODE_AGENT}),
            policies_to_train=sorted(trained),
        )
    try:
        config.validate()
    except (ValueError, TypeError, KeyError) as err:
        text = str(err).strip().splitlines()
        raise ConfigError(f"RLlib rejects these settings: {text[0] if text else err!r}",
                          "train.rllib") from None  # fmt: skip
    return config


def map_agent(mapping: Mapping[str, str], agent_id: str, *args: Any, **kwargs: Any) -> str:
    """RLlib's ``policy_mapping_fn``: the policy of ``agent_id`` (picklable with ``partial``)."""
    return mapping[agent_id]


def steps_per_iteration(config: Any) -> int:
    """Env steps one ``algo.train()`` samples (RLlib's total train batch size)."""
    return int(config.total_train_batch_size)
