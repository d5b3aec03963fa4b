"""RLlib with agents that enter from inflows and leave mid-episode: the multi-agent merge.

The wrapper's per-step dictionaries keep RLlib's multi-agent episode as long as the env's (RLlib
ends one as soon as every agent it has seen is done: before the first inflow AV enters, or when
the last AV on the road leaves); a short PPO run counts full-length episodes and the agents'
steps; ``flowrun eval`` rolls its checkpoint out to MCAP logs that hold the RL cars."""

from __future__ import annotations

import json
import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("ray.rllib", reason="needs the rllib extra: pip install 'flowrun[rllib]'")
pytest.importorskip("pettingzoo", reason="needs the multiagent extra")

import ray
from ray.rllib.env.multi_agent_episode import MultiAgentEpisode
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.loading.loader import load_config
from flowrun.recording.reader import open_log
from flowrun.training.rllib import train_rllib
from flowrun.training.rllib.envs import create_env, env_config_of
from flowrun.training.rllib.options import EPISODE_AGENT

pytestmark = [pytest.mark.rllib, pytest.mark.sumo]

CONFIG = Path(__file__).resolve().parent.parent / "configs" / "rllib_multiagent_merge.yaml"
HORIZON = 100  # 100 s (5 x 0.2 s per step): AVs enter, and some leave, within it
SHORT = [
    f"env.horizon={HORIZON}", "train.total_timesteps=200", "train.num_env_runners=0",
    "train.eval_freq=0", "train.checkpoint_freq=100",
    "train.rllib={train_batch_size_per_learner: 100, minibatch_size: 50, num_epochs: 1}",
]  # fmt: skip


def _rollout(env: Any, episode: MultiAgentEpisode) -> dict[str, Any]:
    """Step the RLlib env with zero actions through RLlib's own episode bookkeeping."""
    obs, infos = env.reset(seed=0)
    episode.add_env_reset(observations=obs, infos=infos)
    seen = {"reset": set(obs), "entered": set(), "left": set(), "steps": 0}
    while not episode.is_done:
        actions = {a: np.zeros(1, np.float32) for a in episode.get_agents_to_act()}
        before = set(episode.agent_ids)
        obs, rewards, terms, truncs, infos = env.step(actions)
        episode.add_env_step(observations=obs, actions=actions, rewards=rewards, infos=infos,
                             terminateds=terms, truncateds=truncs)  # fmt: skip
        seen["steps"] += 1
        seen["entered"] |= set(obs) - before
        seen["left"] |= {a for a, t in terms.items() if t and a != "__all__"}
        seen["env_over"] = bool(terms["__all__"] or truncs["__all__"])
    return seen


def test_rllib_episode_lasts_the_env_episode_while_agents_enter_and_leave() -> None:
    cfg = load_config(CONFIG, [f"env.horizon={HORIZON}"])
    env = create_env(env_config_of(cfg))
    try:
        episode = MultiAgentEpisode(observation_space=env.observation_spaces,
                                    action_space=env.action_spaces)  # fmt: skip
        seen = _rollout(env, episode)
    finally:
        env.close()
    assert seen["reset"] == {EPISODE_AGENT}  # no AV on the road at the start
    assert seen["steps"] == HORIZON and seen["env_over"] and episode.is_truncated
    vehicles = {a for a in seen["entered"] if a != EPISODE_AGENT}
    assert len(vehicles) >= 3 and all(a.startswith("flow_1.") for a in vehicles)
    assert seen["left"] and seen["left"] < vehicles  # some left mid-episode, some stayed
    for agent in seen["left"]:  # terminated when it left, not truncated at the horizon
        assert episode.agent_episodes[agent].is_terminated
    # the episode agent acted once and observed at reset and at the end: one agent step
    assert len(episode.agent_episodes[EPISODE_AGENT]) == 1


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    ray.init(address="local", num_cpus=2, include_dashboard=False, logging_level=logging.WARNING)
    yield
    ray.shutdown()


def test_ppo_on_the_merge_counts_full_episodes_and_eval_logs_the_rl_cars(
    local_ray: None, tmp_path: Path
) -> None:
    cfg = load_config(CONFIG, SHORT)
    result = train_rllib(cfg, out=tmp_path / "runs", argv=["flowrun", "train"])
    assert (result.status, result.timesteps) == ("complete", 200)
    run = result.run_dir
    lines = [json.loads(x) for x in (run / "progress.jsonl").read_text().splitlines()]
    assert [(x["iteration"], x["timesteps"]) for x in lines] == [(1, 100), (2, 200)]
    # RLlib's episodes are the env's: full horizon (not cut where no AV was on the road)
    assert lines[1]["episode_len_mean"] == HORIZON
    # agent steps: AVs on the road at some steps only, several at others
    steps = [x["agent_steps"] for x in lines]
    assert 0 < steps[0] < steps[1] and steps[1] != 200
    mapping = json.loads((run / "policies.json").read_text())
    assert set(mapping.values()) == {"shared"} and EPISODE_AGENT not in mapping
    modules = run / "final_checkpoint" / "learner_group" / "learner" / "rl_module"
    assert (modules / "shared").is_dir()

    evaluated = CliRunner().invoke(app, ["eval", str(run), "--out", str(tmp_path / "ev")])
    assert evaluated.exit_code == 0, evaluated.output
    (policy_log,) = (tmp_path / "ev").glob("*/policy_0.mcap")
    log = open_log(policy_log)
    assert log.frame_count == HORIZON * 5 + 1  # reset + 5 simulation steps per env step
    rl_ids = {i for f in log.frames() for i, rl in zip(f.ids, f.is_rl, strict=True) if rl}
    assert len(rl_ids) >= 3 and all(i.startswith("flow_1.") for i in rl_ids)
    commanded = [a for f in log.frames() for a in f.accel_cmd[f.is_rl] if np.isfinite(a)]
    assert commanded and np.all(np.abs(commanded) <= 1.5 + 1e-9)  # the policy's, in its box
