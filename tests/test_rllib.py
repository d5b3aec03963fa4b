"""RLlib training (``train.backend: rllib``), real and short: PPO on the ring with 2 env
runners and on the multi-agent traffic-light grid, each for 2 iterations on one local Ray
instance, and Flow's multi-ring env from its flow_params for 1; a checkpoint, resume
continuing RLlib's iteration counter, evaluation of a checkpoint to MCAP logs read back; bad
settings as one-line errors (no Ray needed for those)."""

from __future__ import annotations

import json
import logging
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("ray.rllib", reason="needs the rllib extra: pip install 'flowrun[rllib]'")
pytest.importorskip("pettingzoo", reason="needs the multiagent extra")

import ray

from flowrun.errors import ConfigError, TrainingError
from flowrun.loading.loader import load_config
from flowrun.recording.reader import open_log
from flowrun.training.rllib import (
    INSTALL_HINT,
    evaluate_rllib,
    is_rllib_run,
    require_ray,
    train_rllib,
)
from flowrun.training.rllib.cluster import check_reachable, host_port, resolve_address
from flowrun.training.rllib.envs import policy_mapping, probe_agents
from flowrun.training.rllib.evaluate import load_policies
from flowrun.training.rllib.options import check_train_config
from flowrun.training.trainer import resume_config

pytestmark = [pytest.mark.rllib]

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
TINY = "train.rllib={train_batch_size_per_learner: 200, minibatch_size: 100, num_epochs: 1}"
RING = [
    "env.horizon=100", "env.warmup_steps=10", "train.total_timesteps=400",
    "train.num_env_runners=2", "train.eval_freq=200", "train.eval_episodes=1",
    "train.checkpoint_freq=200", TINY,
]  # fmt: skip
GRID = [
    "env.horizon=50", "train.total_timesteps=200", "train.num_env_runners=0",
    "train.eval_freq=0", "train.checkpoint_freq=200", TINY,
]  # fmt: skip


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    """One local Ray for the module (train_rllib uses it and leaves it running)."""
    ray.init(address="local", num_cpus=2, include_dashboard=False, logging_level=logging.WARNING)
    yield
    ray.shutdown()


@pytest.fixture(scope="module")
def ring_run(local_ray: None, tmp_path_factory: pytest.TempPathFactory) -> Path:
    cfg = load_config(CONFIGS / "rllib_ring.yaml", RING)
    seen: list[tuple[int, int]] = []
    result = train_rllib(
        cfg, out=tmp_path_factory.mktemp("runs"), argv=["flowrun", "train"],
        progress=lambda done, total, _: seen.append((done, total)),
    )  # fmt: skip
    assert result.status == "complete" and result.timesteps == 400
    assert seen == [(200, 400), (400, 400)]
    return result.run_dir


def _lines(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


# ---------------------------------------------------------------- before Ray starts here
def test_unreachable_cluster_is_an_error_and_leaves_no_run_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    if ray.is_initialized():
        pytest.skip("Ray is already running in this process (run this test first)")
    monkeypatch.setenv("RAY_ADDRESS", "127.0.0.1:1")  # a closed port on this machine
    cfg = load_config(CONFIGS / "rllib_ring.yaml")
    with pytest.raises(TrainingError, match=r"cannot reach the Ray cluster at 127\.0\.0\.1:1"):
        train_rllib(cfg, out=tmp_path)
    assert not ray.is_initialized()
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------- training, single agent
def test_single_agent_run_folder(ring_run: Path) -> None:
    for name in ("config.yaml", "command.txt", "versions.json", "metrics.json"):
        assert (ring_run / name).is_file(), name
    metrics = json.loads((ring_run / "metrics.json").read_text())
    assert metrics["backend"] == "rllib" and metrics["status"] == "complete"
    assert (metrics["iterations"], metrics["timesteps"], metrics["num_env_runners"]) == (2, 400, 2)
    assert json.loads((ring_run / "versions.json").read_text())["ray"] == ray.__version__
    state = json.loads((ring_run / "checkpoints" / "state.json").read_text())
    assert (state["iteration"], state["timesteps"]) == (2, 400)
    assert (ring_run / "checkpoints" / "iter_000001").is_dir()  # checkpoint_freq=200 steps
    assert (ring_run / "final_checkpoint" / "learner_group").is_dir()
    progress = _lines(ring_run / "progress.jsonl")
    assert [p["iteration"] for p in progress] == [1, 2]
    # the best checkpoint is the one of the best evaluation (evaluated every iteration)
    scores = [p["eval_return_mean"] for p in progress]
    assert all(s is not None for s in scores)
    assert metrics["best_eval_return"] == max(scores)
    assert (ring_run / "best_checkpoint" / "learner_group").is_dir()
    assert list((ring_run / "tensorboard").glob("events.out.tfevents.*"))
    assert is_rllib_run(ring_run) and not is_rllib_run(ring_run / "tensorboard")


def test_resume_continues_the_iteration_counter_and_stops_on_request(ring_run: Path) -> None:
    assert json.loads((ring_run / "status.json").read_text())["status"] == "complete"
    cfg = resume_config(ring_run, ["train.total_timesteps=800", "train.eval_freq=0"])
    result = train_rllib(
        cfg, resume_dir=ring_run, argv=["flowrun", "train", "--resume"],
        should_stop=lambda: True,  # as after Ctrl-C: stop after the iteration under way
    )  # fmt: skip
    assert (result.status, result.timesteps, result.resumed_from) == ("interrupted", 600, 400)
    progress = _lines(ring_run / "progress.jsonl")
    assert [(p["iteration"], p["timesteps"]) for p in progress] == [(1, 200), (2, 400), (3, 600)]
    metrics = json.loads((ring_run / "metrics.json").read_text())
    assert (metrics["status"], metrics["iterations"], metrics["resumed_from"]) == (
        "interrupted", 3, 400,
    )  # fmt: skip
    state = json.loads((ring_run / "checkpoints" / "state.json").read_text())
    assert (state["checkpoint"], state["timesteps"]) == ("iter_000003", 600)
    assert json.loads((ring_run / "status.json").read_text())["status"] == "interrupted"
    assert len((ring_run / "command.txt").read_text().splitlines()) == 2
    assert (ring_run / "config.before_400.yaml").is_file()  # the total changed


def test_evaluate_a_checkpoint_to_mcap(ring_run: Path) -> None:
    first = evaluate_rllib(ring_run, episodes=1, model="checkpoints/iter_000002")
    assert first.model == ring_run / "checkpoints" / "iter_000002"
    assert [p.name for p in first.logs] == ["policy_0.mcap", "baseline_0.mcap"]
    policy, baseline = (open_log(p) for p in first.logs)
    assert policy.frame_count == baseline.frame_count == 111  # reset + 10 warm-up + 100 steps
    rl_accel = [f.accel_cmd[f.is_rl][0] for f in policy.frames() if f.step > 10]
    assert np.all(np.abs(rl_accel) <= 1.0 + 1e-9)  # the policy's commands, in the action box
    assert np.ptp(rl_accel) > 0  # ... that change with the observation
    speeds = [f.speed for f in policy.frames()]
    assert not np.allclose(speeds[-1], [f.speed for f in baseline.frames()][-1])
    assert first.out_dir.parent == ring_run / "eval" and first.out_dir.name.endswith("-0")
    metrics = json.loads((first.out_dir / "metrics.json").read_text())
    assert metrics["backend"] == "rllib" and metrics["policy"][0]["collisions"] == 0
    assert (metrics["status"], metrics["run_status"]) == ("complete", "interrupted")
    # deterministic policy, same seeds: the same episode again
    again = evaluate_rllib(ring_run, episodes=1, model="checkpoints/iter_000002")
    assert again.policy[0].episode_return == first.policy[0].episode_return
    assert [f.speed.tolist() for f in open_log(again.logs[0]).frames()] == [
        s.tolist() for s in speeds
    ]


def test_flows_visualizer_rllib_replays_a_checkpoint(
    ring_run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from flowrun.visualize.visualizer_rllib import create_parser, visualizer_rllib

    argv = [str(ring_run), "2", "--num_rollouts", "2", "--horizon", "20", "--gen_emission"]
    result = visualizer_rllib(create_parser().parse_args(argv))
    assert result.model == ring_run / "checkpoints" / "iter_000002"
    assert [p.name for p in result.logs[:2]] == ["policy_0.mcap", "policy_1.mcap"]
    assert open_log(result.logs[0]).frame_count == 31  # reset + 10 warm-up + --horizon 20
    out = capsys.readouterr().out
    assert f"Round 1, return: {result.policy[1].episode_return}" in out
    returns = [m.episode_return for m in result.policy]
    assert f"Average, std returns: {np.mean(returns)}, {np.std(returns)}" in out
    emission = result.out_dir / "policy_0_emission.csv"
    header, *rows = emission.read_text().splitlines()
    assert header.startswith("time,id,x,y,speed") and len(rows) == 22 * 31
    with pytest.raises(TrainingError, match="--run DQN differs from the algorithm"):
        visualizer_rllib(create_parser().parse_args([str(ring_run), "2", "--run", "DQN"]))


# ---------------------------------------------------------------- training, multi-agent
def test_multi_agent_grid_trains_evaluates_and_repeats(local_ray: None, tmp_path: Path) -> None:
    """Sampling in the driver (0 env runners): one shared policy for the 9 lights."""
    cfg = load_config(CONFIGS / "multiagent_grid.yaml", GRID)
    result = train_rllib(cfg, out=tmp_path, argv=["flowrun", "train"])
    run = result.run_dir
    assert (result.status, result.timesteps) == ("complete", 200)
    mapping = json.loads((run / "policies.json").read_text())
    assert mapping == {f"center{i}": "shared" for i in range(9)}
    modules = run / "final_checkpoint" / "learner_group" / "learner" / "rl_module"
    assert (modules / "shared").is_dir()
    evaluation = evaluate_rllib(run, episodes=1, model="final")
    log = open_log(evaluation.logs[0])
    assert log.frame_count == 51 and log.has_signals
    states = [s for frame in log.signals() for s in frame.states]
    assert any("y" in s for s in states)  # the lights switched on the policy's requests
    assert evaluation.policy[0].collisions == 0
    # same seed => same training (RLlib on a local Ray with this setup; measured the same
    # with 1 and 2 env runners too)
    again = train_rllib(cfg, out=tmp_path, argv=["flowrun", "train"]).run_dir
    assert _lines(again / "progress.jsonl") == [
        {**line, "time_this_iter_s": line2["time_this_iter_s"]}
        for line, line2 in zip(
            _lines(run / "progress.jsonl"), _lines(again / "progress.jsonl"), strict=True
        )
    ]
    weights = [
        load_policies(r / "final_checkpoint")["shared"].module.state_dict() for r in (run, again)
    ]
    assert weights[0].keys() == weights[1].keys()
    assert all(np.array_equal(weights[0][k], weights[1][k]) for k in weights[0])


def test_flows_lord_of_the_rings_trains_and_evaluates(local_ray: None, tmp_path: Path) -> None:
    """Flow's ``MultiWaveAttenuationPOEnv`` from its flow_params: 2 rings, one AV agent on
    each, one shared policy, one iteration of 100 env steps (2 episodes of 50)."""
    from flowrun.loading.flow_params import from_flow_params
    from flowrun.loading.loader import override_config
    from tests.test_multiagent_rings import flow_params

    cfg = override_config(from_flow_params(flow_params(horizon=50)).config, [
        "train.backend=rllib", "train.total_timesteps=100", "train.num_env_runners=0",
        "train.eval_freq=0", "train.checkpoint_freq=100",
        "train.rllib={train_batch_size_per_learner: 100, minibatch_size: 50, num_epochs: 1}",
    ])  # fmt: skip
    result = train_rllib(cfg, out=tmp_path, argv=["flowrun", "train"])
    run = result.run_dir
    assert (result.status, result.timesteps) == ("complete", 100)
    assert json.loads((run / "policies.json").read_text()) == {
        "rl_0_0": "shared", "rl_1_0": "shared",
    }  # fmt: skip
    [progress] = _lines(run / "progress.jsonl")
    assert (progress["agent_steps"], progress["episode_len_mean"]) == (200, 50.0)
    # each agent earns its ring's reward, in [0, 1] per step: 2 agents x 50 steps at most
    assert 0.0 < progress["episode_return_mean"] <= 100.0
    evaluation = evaluate_rllib(run, episodes=1, model="final")
    log = open_log(evaluation.logs[0])
    assert log.frame_count == 71  # reset + 20 warm-up + 50 steps
    assert [f.is_rl.sum() for f in log.frames()][-1] == 2
    assert evaluation.policy[0].collisions == 0


# ---------------------------------------------------------------- settings, no training
def test_policy_mapping_modes() -> None:
    ring = load_config(CONFIGS / "multiagent_ring.yaml")
    agents = probe_agents(ring)
    assert agents == ["rl_0", "rl_1"]
    assert policy_mapping(ring, agents, "shared") == {"rl_0": "shared", "rl_1": "shared"}
    assert policy_mapping(ring, agents, "group") == {"rl_0": "rl", "rl_1": "rl"}
    assert policy_mapping(ring, agents, "agent") == {"rl_0": "rl_0", "rl_1": "rl_1"}
    merge = load_config(CONFIGS / "multiagent_merge.yaml")
    merge_agents = probe_agents(merge)
    assert merge_agents is not None and len(merge_agents) == 35
    groups = set(policy_mapping(merge, merge_agents, "group").values())
    assert groups == {"rl"}  # inflow AVs belong to their inflow's vehicle type
    assert probe_agents(load_config(CONFIGS / "rllib_ring.yaml")) is None


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("train.rllib={lrr: 0.1}", "unknown RLlib PPO option 'lrr' (did you mean 'lr'?)"),
        ("train.rllib={num_env_runners: 3}", "sets 'num_env_runners' from train.num_env_runners"),
        ("train.rllib={num_envs_per_env_runner: 2}", "one simulation per process"),
        ("train.rllib={lr: fast}", "expected a number, got 'fast'"),
        ("train.rllib={num_epochs: 2.5}", "expected a whole number"),
        ("train.algorithm=SAC", "trains PPO only"),
        ("train.policies=shard", "did you mean 'shared'"),
        ("train.hyperparams={n_steps: 10}", "stable-baselines3 names"),
        ("train.policy_kwargs={net_arch: [8]}", "train.rllib.model_config"),
        ("train.normalize=true", "VecNormalize is stable-baselines3's"),
    ],
)
def test_bad_settings_are_one_line_config_errors(override: str, message: str) -> None:
    cfg = load_config(CONFIGS / "rllib_ring.yaml", [override])
    assert cfg.train is not None
    with pytest.raises(ConfigError) as err:
        check_train_config(cfg.train)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_flows_lambda_name_is_rlliibs_lambda_() -> None:
    cfg = load_config(CONFIGS / "rllib_ring.yaml")
    assert cfg.train is not None
    sections = check_train_config(cfg.train)
    assert sections["training"]["lambda_"] == 0.97
    assert sections["rl_module"]["model_config"] == {"fcnet_hiddens": [64, 64]}


def test_unreachable_ray_address_fails_fast(monkeypatch: pytest.MonkeyPatch) -> None:
    assert host_port("ray://head:10001") == ("head", 10001)
    assert host_port("10.0.0.5") == ("10.0.0.5", 6379)
    monkeypatch.setenv("RAY_ADDRESS", "127.0.0.1:1")
    assert resolve_address(None) == "127.0.0.1:1"
    assert resolve_address("auto") == "auto"
    with pytest.raises(TrainingError, match=r"cannot reach the Ray cluster at 127\.0\.0\.1:1"):
        check_reachable(resolve_address(None) or "", timeout=2.0)


def test_missing_extra_names_the_install_command(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ray.rllib", None)
    with pytest.raises(TrainingError) as err:
        require_ray()
    assert INSTALL_HINT in str(err.value)


def test_flowrun_train_and_eval_commands_run_the_rllib_backend(
    local_ray: None, tmp_path: Path
) -> None:
    from typer.testing import CliRunner

    from flowrun.cli.main import app

    runner = CliRunner()
    sets = [arg for o in GRID for arg in ("--set", o)]
    trained = runner.invoke(
        app, ["train", str(CONFIGS / "multiagent_grid.yaml"), *sets, "--out", str(tmp_path)]
    )
    assert trained.exit_code == 0, trained.output
    run_dir = next(tmp_path.glob("*/*"))
    assert is_rllib_run(run_dir)
    assert json.loads((run_dir / "status.json").read_text())["status"] == "complete"
    evaluated = runner.invoke(
        app, ["eval", str(run_dir), "--set", "env.horizon=20", "--out", str(tmp_path / "ev")]
    )
    assert evaluated.exit_code == 0, evaluated.output
    assert "final_checkpoint, 1 episode(s)" in evaluated.output
    assert list((tmp_path / "ev").glob("*/policy_0.mcap"))


def test_ray_address_with_the_sb3_backend_is_one_clear_error(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from flowrun.cli.main import app

    args = ["train", str(CONFIGS / "ring_wave.yaml"), "--ray-address", "127.0.0.1:1"]
    result = CliRunner().invoke(app, [*args, "--out", str(tmp_path)])
    assert result.exit_code == 1
    assert "--ray-address is for train.backend: rllib" in result.output
    assert not list(tmp_path.iterdir())
