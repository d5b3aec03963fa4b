"""The driver's side of rollouts stepped in the env processes (:mod:`flowrun.training.rollout`).

:func:`with_worker_rollouts` gives an on-policy SB3 algorithm (PPO, A2C, TRPO) a
``collect_rollouts`` that asks every env process for its segment of ``n_steps`` at once and
fills SB3's rollout buffer with them: the same buffer, returns and advantages as SB3's own loop
(timeouts bootstrapped with the value of the last observation, rewards normalised step after
step by ``VecNormalize``), the callbacks called once per vectorised step after the segments
arrive. Policies it cannot copy (not an ``MlpPolicy`` with Gaussian actions, gSDE) and envs not
built with ``make_vec_env(..., worker_rollouts=True)`` keep SB3's own loop.
"""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING, Any

import numpy as np

from flowrun.training.deps import require
from flowrun.training.rollout import Mlp, NumpyActor, ObsStats, Segment

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.vec_env import VecEnv, VecNormalize

ACTIVATIONS = {"Tanh": "tanh", "ReLU": "relu"}


def with_worker_rollouts(cls: type[BaseAlgorithm]) -> type[BaseAlgorithm]:
    """``cls`` with rollouts stepped in the env processes (``cls`` itself when it is not an
    on-policy algorithm)."""
    on_policy = require("stable_baselines3.common.on_policy_algorithm").OnPolicyAlgorithm
    if not issubclass(cls, on_policy):
        return cls
    return _subclass(cls)


@cache
def _subclass(cls: type[BaseAlgorithm]) -> type[BaseAlgorithm]:
    return type(cls.__name__, (WorkerRollouts, cls), {"__module__": cls.__module__})


def numpy_actor(policy: Any) -> NumpyActor | None:
    """A numpy copy of the acting half of an SB3 ``ActorCriticPolicy`` MLP with Gaussian
    actions, or ``None`` for any other policy."""
    torch = require("torch")
    distributions = require("stable_baselines3.common.distributions")
    torch_layers = require("stable_baselines3.common.torch_layers")
    mlp = getattr(policy, "mlp_extractor", None)
    if (
        mlp is None
        or getattr(policy, "use_sde", True)
        or getattr(policy, "squash_output", True)
        or not isinstance(policy.action_dist, distributions.DiagGaussianDistribution)
        or not isinstance(policy.pi_features_extractor, torch_layers.FlattenExtractor)
    ):
        return None
    mean = _mlp([*mlp.policy_net, policy.action_net], torch.nn)
    if mean is None:
        return None
    space = policy.action_space
    return NumpyActor(
        mean, policy.log_std.detach().cpu().numpy().astype(np.float64),
        np.asarray(space.low, np.float64), np.asarray(space.high, np.float64),
    )


def _mlp(modules: list[Any], nn: Any) -> Mlp | None:
    weights: list[np.ndarray] = []
    biases: list[np.ndarray] = []
    activations: list[str] = []
    for module in modules:
        if isinstance(module, nn.Linear):
            weights.append(module.weight.detach().cpu().numpy().astype(np.float64).T.copy())
            biases.append(module.bias.detach().cpu().numpy().astype(np.float64).copy())
            activations.append("")
        elif type(module).__name__ in ACTIVATIONS and activations and not activations[-1]:
            activations[-1] = ACTIVATIONS[type(module).__name__]
        else:
            return None
    return Mlp(tuple(weights), tuple(biases), tuple(activations))


def obs_stats(normalize: VecNormalize | None) -> ObsStats | None:
    """A copy of ``VecNormalize``'s observation statistics (``None``: not normalised)."""
    if normalize is None or not normalize.norm_obs:
        return None
    rms = normalize.obs_rms
    if isinstance(rms, dict):
        return None  # a dict observation space has no numpy policy anyway
    return ObsStats(rms.mean.copy(), rms.var.copy(), float(rms.count),
                    float(normalize.clip_obs), float(normalize.epsilon))


class WorkerRollouts:
    """Mixin for an ``OnPolicyAlgorithm``: :meth:`collect_rollouts` in the env processes."""

    def collect_rollouts(
        self, env: VecEnv, callback: Any, rollout_buffer: Any, n_rollout_steps: int
    ) -> bool:
        """SB3's ``collect_rollouts``, the steps taken in the env processes."""
        model: Any = self
        actor = None
        if getattr(env, "worker_rollouts", False) and rollout_buffer.buffer_size == n_rollout_steps:
            actor = numpy_actor(model.policy)
        if actor is None:
            return bool(super().collect_rollouts(  # type: ignore[misc]
                env, callback, rollout_buffer, n_rollout_steps))
        model.policy.set_training_mode(False)
        rollout_buffer.reset()
        callback.on_rollout_start()
        normalize = model.get_vec_normalize_env()
        entropy = (int(model.seed or 0), int(model.num_timesteps))
        segments: list[Segment] = env.env_method(
            "rollout", actor, obs_stats(normalize), n_rollout_steps, entropy
        )
        rewards = _rewards(segments, normalize)
        _fill(rollout_buffer, segments, rewards, model._last_episode_starts)
        last_values = _evaluate(model, rollout_buffer, segments)
        last_obs = np.stack([s.next_obs[-1] for s in segments])
        dones = np.stack([s.dones for s in segments], axis=1)
        if not _step_callbacks(model, callback, segments, rollout_buffer.rewards, dones):
            return False
        model._last_obs = last_obs if normalize is None else normalize.normalize_obs(last_obs)
        model._last_episode_starts = dones[-1]
        rollout_buffer.compute_returns_and_advantage(last_values=last_values, dones=dones[-1])
        callback.update_locals({"rollout_buffer": rollout_buffer, "dones": dones[-1]})
        callback.on_rollout_end()
        return True


def _evaluate(model: Any, buffer: Any, segments: list[Segment]) -> Any:
    """Values and log-probabilities of the buffer's steps from the torch policy, as SB3's loop
    computes them; a timed-out episode's last reward plus ``gamma`` times the value of its
    last observation. Returns the values of the observations the next rollout starts from."""
    torch = require("torch")
    policy = model.policy
    n = buffer.buffer_size
    obs = torch.as_tensor(buffer.observations.reshape(n * len(segments), -1))
    actions = torch.as_tensor(buffer.actions.reshape(n * len(segments), -1))
    with torch.no_grad():
        values, log_probs, _ = policy.evaluate_actions(obs, actions)
        buffer.values[:] = values.numpy().reshape(n, len(segments))
        buffer.log_probs[:] = log_probs.numpy().reshape(n, len(segments))
        cut = [(t, rank, o) for rank, s in enumerate(segments) for t, o in s.timeouts.items()]
        if cut:
            ends = policy.predict_values(torch.as_tensor(np.stack([o for _, _, o in cut])))
            for (t, rank, _), value in zip(cut, ends.numpy().ravel(), strict=True):
                buffer.rewards[t, rank] += model.gamma * value
        last = np.stack([s.last_obs for s in segments])
        return policy.predict_values(torch.as_tensor(last)).flatten()


def _rewards(segments: list[Segment], normalize: VecNormalize | None) -> np.ndarray:
    """The rewards normalised by ``VecNormalize`` step after step (its statistics updated on
    the way, the observations' too). Shape (n_steps, n_envs), float32."""
    raw = np.stack([s.rewards for s in segments], axis=1)
    dones = np.stack([s.dones for s in segments], axis=1)
    rewards = raw.astype(np.float32)
    if normalize is not None:
        if normalize.training and normalize.norm_obs:
            normalize.obs_rms.update(np.concatenate([s.next_obs for s in segments]))
        for t in range(raw.shape[0]):
            if normalize.training:
                normalize._update_reward(raw[t])
            rewards[t] = normalize.normalize_reward(raw[t])
            normalize.returns[dones[t]] = 0
        normalize.old_obs = np.stack([s.next_obs[-1] for s in segments])
        normalize.old_reward = raw[-1]
    return rewards


def _fill(buffer: Any, segments: list[Segment], rewards: np.ndarray, starts: np.ndarray) -> None:
    """Write the segments into SB3's ``RolloutBuffer`` as its ``add`` would, step by step
    (values and log-probabilities follow in :func:`_evaluate`)."""
    n = rewards.shape[0]
    dones = np.stack([s.dones for s in segments], axis=1)
    buffer.observations[:n] = np.stack([s.obs for s in segments], axis=1).reshape(
        buffer.observations[:n].shape)
    buffer.actions[:n] = np.stack([s.actions for s in segments], axis=1).reshape(
        buffer.actions[:n].shape)
    buffer.rewards[:n] = rewards
    buffer.episode_starts[0] = starts
    buffer.episode_starts[1:n] = dones[:-1]
    buffer.pos = n
    buffer.full = n == buffer.buffer_size


def _step_callbacks(
    model: Any, callback: Any, segments: list[Segment], rewards: np.ndarray, dones: np.ndarray
) -> bool:
    """Count the steps and call the callbacks once per vectorised step, as SB3's loop does
    (``infos`` hold the episode ends, with ``Monitor``'s ``episode`` entries)."""
    n_envs = len(segments)
    ends: dict[int, list[tuple[int, dict[str, Any]]]] = {}
    for rank, segment in enumerate(segments):
        for t, info in segment.episodes:
            ends.setdefault(t, []).append((rank, info))
    for t in range(rewards.shape[0]):
        model.num_timesteps += n_envs
        infos: list[dict[str, Any]] = [{} for _ in range(n_envs)]
        for rank, info in ends.get(t, []):
            infos[rank] = info
        callback.update_locals({"infos": infos, "dones": dones[t], "rewards": rewards[t]})
        if not callback.on_step():
            return False
        if t in ends:
            model._update_info_buffer(infos, dones[t])
    return True
