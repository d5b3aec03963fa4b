"""The whole experiment as one typed value: what a YAML file holds, section by section."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from flowrun.config.params import (
    EnvParams,
    InitialConfig,
    NetParams,
    SumoParams,
    VehicleParams,
)
from flowrun.config.signal_control import TrafficLightsConfig


@dataclass(frozen=True)
class NetworkConfig:
    """``network:`` section: the network type plus its ``additional_params`` (flattened in YAML).

    YAML ``network: {type: ring, length: 230}`` is ``NetworkConfig("ring", NetParams({...}))``.
    """

    type: str = "ring"
    net_params: NetParams = field(default_factory=NetParams)


@dataclass(frozen=True)
class TrainConfig:
    """``train:`` section: stable-baselines3 training.

    Attributes:
        algorithm: ``PPO``, ``A2C``, ``SAC``, ``TD3``, ``DDPG`` or ``TRPO``.
        total_timesteps: environment steps to train for (over all envs).
        n_envs: parallel environments, one subprocess each.
        seed: training seed; ``None`` uses ``sim.seed``.
        policy: SB3 policy name.
        policy_kwargs: passed to the policy (e.g. ``net_arch``).
        hyperparams: algorithm arguments under SB3's own names (validated against its signature).
        normalize: wrap the envs in ``VecNormalize``.
        eval_freq: evaluate every this many environment steps (0 = never during training).
        eval_episodes: episodes per evaluation and in the final evaluation.
        eval_backend: where the periodic evaluation runs its episodes: ``sumo`` (default) or
            ``numpy`` (single-lane rings only: the numpy backend's rings, which equal SUMO's to
            1e-9 m/s, all episodes stepped together; about a fifth of the cost).
        best_by: what picks ``best_model.zip`` among the periodic evaluations:
            ``speed_ratio`` (default: the worst episode's last-half mean speed relative to the
            all-human baseline of the same episode) or ``return`` (the mean evaluation-mode
            return: a benchmark's own metric, e.g. the whole episode's mean speed).
        common_random_numbers: ARS only: every candidate of an update plays the same seeded
            episode(s) (seed ``seed + 20000 + update``), so the candidates are ranked by their
            weights rather than by the traffic's own randomness (common random numbers).
        checkpoint_freq: save a checkpoint every this many environment steps (0 = never).
        backend: ``sb3`` (stable-baselines3, default) or ``rllib`` (Ray RLlib).
        num_env_runners: RLlib only: env runners (one process and one SUMO each); ``None``
            uses ``n_envs``; 0 samples in the driver process.
        rllib: RLlib only: PPO settings under RLlib's own names (``lr``, ``gamma``,
            ``train_batch_size_per_learner``, ``minibatch_size``, ``num_epochs``, ...),
            checked by ``flowrun.training.rllib``.
        policies: RLlib multi-agent only: ``shared`` (one policy for all agents), ``group``
            (one per vehicle group) or ``agent`` (one per agent).
    """

    algorithm: str = "PPO"
    total_timesteps: int = 100_000
    n_envs: int = 1
    seed: int | None = None
    policy: str = "MlpPolicy"
    policy_kwargs: dict[str, Any] = field(default_factory=dict)
    hyperparams: dict[str, Any] = field(default_factory=dict)
    normalize: bool = False
    eval_freq: int = 0
    eval_episodes: int = 1
    eval_backend: str = "sumo"
    best_by: str = "speed_ratio"
    common_random_numbers: bool = False
    checkpoint_freq: int = 0
    backend: str = "sb3"
    num_env_runners: int | None = None
    rllib: dict[str, Any] = field(default_factory=dict)
    policies: str = "shared"


@dataclass(frozen=True)
class ExperimentConfig:
    """One experiment: Flow's ``flow_params`` bundle as typed data.

    Attributes:
        name: experiment name (names the run folder ``runs/<name>/...``).
        sim: simulation settings.
        env: environment settings.
        network: network type and parameters.
        vehicles: vehicle groups.
        initial: initial placement.
        traffic_lights: signal programs (Flow's ``tls``) and the baseline signal controller.
        train: training settings, for ``flowrun train``.
        source: the YAML file the config was loaded from (``None`` when built in Python). Not a
            YAML key and not compared: an import-path ``env.class`` is also looked for next to
            this file.
    """

    name: str
    sim: SumoParams = field(default_factory=SumoParams)
    env: EnvParams = field(default_factory=EnvParams)
    network: NetworkConfig = field(default_factory=NetworkConfig)
    vehicles: VehicleParams = field(default_factory=VehicleParams)
    initial: InitialConfig = field(default_factory=InitialConfig)
    traffic_lights: TrafficLightsConfig = field(default_factory=TrafficLightsConfig)
    train: TrainConfig | None = None
    source: str | None = field(default=None, compare=False, metadata={"yaml": False})
