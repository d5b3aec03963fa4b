"""Parallel training environments: one SUMO per subprocess (libsumo runs one per process),
or, with ``sim.backend: numpy``, all the rings stepped together in this process."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium

from flowrun.config.model import ExperimentConfig
from flowrun.training.deps import require

if TYPE_CHECKING:
    from stable_baselines3.common.vec_env import VecEnv


@dataclass(frozen=True)
class EnvFactory:
    """Picklable ``() -> env`` for ``SubprocVecEnv``: the config's env in a ``Monitor``.

    Attributes:
        cfg: the experiment.
        monitor_file: where ``Monitor`` writes episode returns (``None``: nowhere).
        seeds: reset seeds used in turn, over and over (``None``: the env's own generator).
        rank: the env's index in its vectorised env.
        rollouts: wrap the ``Monitor`` in a :class:`~flowrun.training.rollout.RolloutEnv`
            (whole rollout segments stepped in the env's process).
    """

    cfg: ExperimentConfig
    monitor_file: str | None = None
    seeds: tuple[int, ...] | None = None
    rank: int = 0
    rollouts: bool = False

    def __call__(self) -> gymnasium.Env[Any, Any]:
        """Build the environment (in the process that calls it)."""
        from flowrun.envs.factory import make_env

        monitor = require("stable_baselines3.common.monitor").Monitor
        env: gymnasium.Env[Any, Any] = make_env(self.cfg)
        if self.seeds:
            env = CycleSeeds(env, self.seeds)
        env = monitor(env, filename=self.monitor_file, info_keywords=("mean_speed",))
        if self.rollouts:
            from flowrun.training.rollout import RolloutEnv

            env = RolloutEnv(env, self.rank)
        return env


class CycleSeeds(gymnasium.Wrapper):
    """Resets with ``seeds[0]``, ``seeds[1]``, ... in turn, so evaluations repeat exactly."""

    def __init__(self, env: gymnasium.Env[Any, Any], seeds: tuple[int, ...]) -> None:
        super().__init__(env)
        self._seeds = seeds
        self._count = 0

    def reset(self, **kwargs: Any) -> Any:
        """Reset with the next seed of the cycle (a ``seed`` argument is ignored)."""
        kwargs["seed"] = self._seeds[self._count % len(self._seeds)]
        self._count += 1
        return self.env.reset(**kwargs)


def make_vec_env(
    cfg: ExperimentConfig,
    n_envs: int,
    seed: int,
    monitor_dir: Path | None = None,
    subprocess: bool = True,
    cycle_seeds: tuple[int, ...] | None = None,
    worker_rollouts: bool = False,
) -> VecEnv:
    """``n_envs`` environments of a config; env ``rank`` is seeded ``seed + rank``.

    Args:
        cfg: the experiment.
        n_envs: number of environments.
        seed: base seed.
        monitor_dir: folder for one ``Monitor`` CSV per env (``None``: none written).
        subprocess: one subprocess per env (required for more than one env); ``False``
            builds a single env in this process.
        cycle_seeds: reset seeds each env uses in turn (for repeatable evaluations).
        worker_rollouts: let an on-policy algorithm step whole rollouts in the env
            processes (:mod:`flowrun.training.worker_rollouts`; subprocesses only): the
            returned env's ``worker_rollouts`` attribute is then true.

    With ``sim.backend: numpy`` the ``n_envs`` rings run in this process as one
    :class:`~flowrun.fastring.vec_env.RingVecEnv` (``subprocess`` does not apply) in a
    ``VecMonitor``; a config the backend cannot run raises ``ConfigError`` here.
    """
    vec = require("stable_baselines3.common.vec_env")
    if cfg.sim.backend == "numpy":
        return _numpy_vec_env(cfg, n_envs, seed, monitor_dir, cycle_seeds)
    factories = [
        EnvFactory(
            cfg, None if monitor_dir is None else str(monitor_dir / f"env_{rank}"), cycle_seeds,
            rank, worker_rollouts and subprocess,
        )
        for rank in range(n_envs)
    ]
    if subprocess:
        venv: VecEnv = vec.SubprocVecEnv(factories, start_method="forkserver")
        venv.worker_rollouts = worker_rollouts  # type: ignore[attr-defined]
    else:
        if n_envs != 1:
            raise ValueError("more than one env needs subprocesses (libsumo: one SUMO a process)")
        venv = vec.DummyVecEnv(factories)
    venv.seed(seed)
    return venv


def _numpy_vec_env(
    cfg: ExperimentConfig,
    n_envs: int,
    seed: int,
    monitor_dir: Path | None,
    cycle_seeds: tuple[int, ...] | None,
) -> VecEnv:
    """The numpy backend's rings in a ``VecMonitor`` (one CSV for all rings)."""
    from flowrun.fastring.plan import ring_plan
    from flowrun.fastring.vec_env import RingVecEnv

    vec = require("stable_baselines3.common.vec_env")
    rings = RingVecEnv(ring_plan(cfg), n_envs, cycle_seeds)
    filename = None if monitor_dir is None else str(monitor_dir / "rings")
    venv: VecEnv = vec.VecMonitor(rings, filename=filename, info_keywords=("mean_speed",))
    venv.seed(seed)
    return venv


def wrap_normalize(
    venv: VecEnv, stats: Path | None, training: bool, gamma: float = 0.99, rewards: bool = True
) -> VecEnv:
    """Wrap in ``VecNormalize``: fresh, or with the statistics saved at ``stats``.

    Observations are normalised; rewards too while training (discounted with ``gamma``)
    unless ``rewards`` is false (ARS ranks candidates by their raw returns).
    """
    vec = require("stable_baselines3.common.vec_env")
    if stats is not None:
        normalized: VecEnv = vec.VecNormalize.load(str(stats), venv)
        normalized.training = training  # type: ignore[attr-defined]
        if not training:
            normalized.norm_reward = False  # type: ignore[attr-defined]
        return normalized
    return vec.VecNormalize(
        venv, training=training, norm_reward=training and rewards, gamma=gamma
    )
