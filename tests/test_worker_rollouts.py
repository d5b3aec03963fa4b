"""Rollouts stepped in the env processes: the buffer SB3 learns from, seeds, the numpy policy."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from flowrun.loading.loader import load_config
from flowrun.training.rollout import ObsStats
from flowrun.training.vecenv import make_vec_env, wrap_normalize
from flowrun.training.worker_rollouts import numpy_actor, with_worker_rollouts

pytestmark = pytest.mark.train
pytest.importorskip("stable_baselines3")

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "ring_wave.yaml"
SMALL = ["env.horizon=200", "env.warmup_steps=0"]


def _ppo(venv: Any, **kwargs: Any) -> Any:
    from stable_baselines3 import PPO

    return with_worker_rollouts(PPO)(
        "MlpPolicy", venv, n_steps=256, batch_size=128, n_epochs=1, seed=0, device="cpu",
        policy_kwargs={"net_arch": [16, 16]}, **kwargs,
    )


def test_the_buffer_holds_what_the_policy_did_on_the_normalised_observations() -> None:
    from stable_baselines3.common.callbacks import BaseCallback

    cfg = load_config(CONFIG, SMALL)
    venv = wrap_normalize(make_vec_env(cfg, 2, seed=0, worker_rollouts=True), None, True)
    seen: dict[str, Any] = {}

    class Check(BaseCallback):
        def _on_step(self) -> bool:
            seen["steps"] = seen.get("steps", 0) + 1
            return True

        def _on_rollout_end(self) -> None:
            import torch

            buf = self.model.rollout_buffer
            obs = torch.as_tensor(buf.observations.reshape(-1, buf.observations.shape[-1]))
            actions = torch.as_tensor(buf.actions.reshape(-1, buf.actions.shape[-1]))
            with torch.no_grad():
                values, log_prob, _ = self.model.policy.evaluate_actions(obs, actions)
            seen["value_error"] = float(np.abs(values.numpy().ravel()
                                               - buf.values.ravel()).max())
            seen["log_prob_error"] = float(np.abs(log_prob.numpy() - buf.log_probs.ravel()).max())
            seen["starts"] = buf.episode_starts.copy()
            seen["obs"] = buf.observations.copy()

    try:
        model = _ppo(venv)
        model.learn(1024, callback=Check())
        assert type(model).__name__ == "PPO"
        assert seen["steps"] == 512  # one callback step per vectorised step, as SB3's loop
        assert seen["value_error"] < 1e-4 and seen["log_prob_error"] < 1e-3
        # 200-step episodes: the second rollout (steps 256..511) starts one at step 400
        assert seen["starts"][144].all() and seen["starts"].sum() == 2
        assert np.abs(seen["obs"]).max() <= 10.0  # VecNormalize's clip
        assert len(model.ep_info_buffer) == 4  # Monitor's episode infos of both rollouts
        assert venv.obs_rms.count == pytest.approx(2 + 1024, abs=0.01)  # resets + every step
    finally:
        venv.close()


def test_same_seed_same_policy() -> None:
    cfg = load_config(CONFIG, SMALL)
    params = []
    for _ in range(2):
        venv = wrap_normalize(make_vec_env(cfg, 2, seed=5, worker_rollouts=True), None, True)
        try:
            model = _ppo(venv)
            model.learn(512)
            params.append([p.detach().numpy().copy() for p in model.policy.parameters()])
        finally:
            venv.close()
    for a, b in zip(*params, strict=True):
        np.testing.assert_array_equal(a, b)


def test_one_observation_at_a_time_is_running_mean_std_exactly() -> None:
    from stable_baselines3.common.running_mean_std import RunningMeanStd

    rng = np.random.default_rng(1)
    rms = RunningMeanStd(shape=(3,))
    stats = ObsStats(rms.mean.copy(), rms.var.copy(), rms.count, 10.0, 1e-8)
    for _ in range(50):
        x = rng.normal(5.0, 2.0, 3)
        rms.update(x[None])
        stats.update(x)
    np.testing.assert_array_equal(stats.mean, rms.mean)
    np.testing.assert_array_equal(stats.var, rms.var)
    assert stats.count == rms.count


def test_numpy_copy_matches_the_torch_policy_or_declines() -> None:
    import torch
    from stable_baselines3 import PPO

    cfg = load_config(CONFIG, SMALL)
    venv = make_vec_env(cfg, 1, seed=0, subprocess=False)
    try:
        model = PPO("MlpPolicy", venv, seed=0, device="cpu",
                    policy_kwargs={"net_arch": [32, 8], "activation_fn": torch.nn.ReLU})
        copy = numpy_actor(model.policy)
        assert copy is not None
        obs = np.random.default_rng(0).normal(size=(5, venv.observation_space.shape[0]))
        with torch.no_grad():
            tensor = torch.as_tensor(obs, dtype=torch.float32)
            mean = model.policy.get_distribution(tensor).distribution.mean.numpy()
        np.testing.assert_allclose(copy.mean(obs), mean, atol=1e-5)
        sde = PPO("MlpPolicy", venv, use_sde=True, seed=0, device="cpu")
        assert numpy_actor(sde.policy) is None  # SB3's own loop then
    finally:
        venv.close()


@pytest.mark.parametrize("kind", ["LinearPolicy", "MlpPolicy"])
def test_ars_candidates_act_with_numpy_as_the_torch_policy(kind: str) -> None:
    import torch
    from sb3_contrib import ARS

    from flowrun.training.numpy_predict import NumpyPredictor

    cfg = load_config(CONFIG, SMALL)
    venv = make_vec_env(cfg, 1, seed=0, subprocess=False)
    try:
        model = ARS(kind, venv, seed=0, device="cpu",
                    policy_kwargs={"with_bias": True} if kind == "LinearPolicy" else None)
        predictor = NumpyPredictor(model.policy)
        vector = torch.as_tensor(np.random.default_rng(2).normal(
            0, 0.5, model.policy.parameters_to_vector().shape), dtype=torch.float32)
        predictor.load_from_vector(vector)
        obs = np.random.default_rng(0).normal(size=(6, venv.observation_space.shape[0]))
        obs = obs.astype(np.float32)
        expected, _ = model.policy.predict(obs, deterministic=True)
        actions, _ = predictor.predict(obs, deterministic=True)
        assert actions.shape == expected.shape and actions.dtype == expected.dtype
        np.testing.assert_allclose(actions, expected, atol=1e-5)
        assert np.abs(expected).max() > 0.1  # not all clipped to zero
        single, _ = predictor.predict(obs[0])
        np.testing.assert_allclose(single, expected[0], atol=1e-5)
        # one observation gives the batch's row bit for bit (its own path for speed)
        assert single.dtype == actions.dtype
        np.testing.assert_array_equal(single, actions[0])
        wide = obs[1] * 1e3  # far outside the bounds: clipped as the batch clips
        clipped, _ = predictor.predict(wide)
        np.testing.assert_array_equal(clipped, predictor.predict(wide[None])[0][0])
        space = model.policy.action_space
        assert np.all((clipped == space.low) | (clipped == space.high))
    finally:
        venv.close()


def test_lean_async_eval_plays_candidates_as_sb3_contribs_async_eval() -> None:
    import torch
    from sb3_contrib import ARS
    from sb3_contrib.common.vec_env.async_eval import AsyncEval

    from flowrun.training.ars import WorkerEnv
    from flowrun.training.numpy_predict import LeanAsyncEval
    from flowrun.training.vecenv import EnvFactory

    cfg = load_config(CONFIG, ["env.horizon=60", "env.warmup_steps=0"])
    venv = make_vec_env(cfg, 1, seed=0, subprocess=False)
    model = ARS("LinearPolicy", venv, seed=0, device="cpu", policy_kwargs={"with_bias": True})
    venv.close()
    n_params = model.policy.parameters_to_vector().shape[0]
    weights = torch.as_tensor(np.random.default_rng(3).normal(0, 0.3, (4, n_params)),
                              dtype=torch.float32)
    workers = [WorkerEnv(EnvFactory(cfg), 7 + rank, True) for rank in range(2)]
    outcomes = []
    for cls in (AsyncEval, LeanAsyncEval):
        evaluator = (AsyncEval(workers, model.policy, start_method="forkserver")
                     if cls is AsyncEval else LeanAsyncEval(workers, model.policy))
        try:
            results = []
            for _ in range(2):  # twice: the envs and statistics carry on between updates
                evaluator.send_jobs(weights, 4)
                results.append(sorted(evaluator.get_results(), key=lambda r: r[0]))
            outcomes.append((results, evaluator.get_obs_rms()))
        finally:
            evaluator.close()
    (sb3_results, sb3_rms), (lean_results, lean_rms) = outcomes
    for sb3_update, lean_update in zip(sb3_results, lean_results, strict=True):
        for (i, (r1, l1)), (j, (r2, l2)) in zip(sb3_update, lean_update, strict=True):
            assert i == j and list(l1) == list(l2) == [60]
            np.testing.assert_allclose(r2, r1, rtol=1e-4)
    for a, b in zip(sb3_rms, lean_rms, strict=True):
        assert a.count == b.count  # 2 candidates x 2 updates x (1 reset + 60 steps)
        np.testing.assert_allclose(b.mean, a.mean, rtol=1e-5)
        np.testing.assert_allclose(b.var, a.var, rtol=1e-4)
