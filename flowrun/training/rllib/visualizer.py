"""Flow's ``visualizer_rllib``: replay an RLlib checkpoint, with Flow's command-line arguments.

Flow reads Ray's result folder; flowrun's RLlib runs keep their config and checkpoints in the
run folder, so ``result_dir`` is that folder (``runs/<name>/<run>``) and ``checkpoint_num``
picks ``checkpoints/iter_<n>`` (or ``best`` / ``final``). The rollouts are
:func:`~flowrun.training.rllib.evaluate.evaluate_rllib`'s (policy and all-human baseline,
logged to MCAP in ``<run>/eval/``)::

    from flowrun.visualize.visualizer_rllib import create_parser, visualizer_rllib
    visualizer_rllib(create_parser().parse_args(["runs/ring/<run>", "2", "--num_rollouts", "3"]))
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from flowrun.errors import TrainingError
from flowrun.training.evaluate import EvalResult, eval_config

#: Flow's render modes; flowrun logs every rollout to MCAP instead of opening a window.
RENDER_MODES = ("sumo_web3d", "drgb", "sumo_gui", "no_render")


def create_parser() -> argparse.ArgumentParser:
    """Flow's parser: ``result_dir checkpoint_num [--run] [--num_rollouts] [--gen_emission]
    [--evaluate] [--render_mode] [--save_render] [--horizon]``."""
    parser = argparse.ArgumentParser(
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="[flowrun] Replay an RLlib checkpoint of a flowrun run (Flow's visualizer).",
        epilog="python -m flowrun.visualize.visualizer_rllib runs/ring/<run> 2 --num_rollouts 1",
    )
    parser.add_argument("result_dir", type=str, help="the RLlib run folder (runs/<name>/<run>)")
    parser.add_argument(
        "checkpoint_num", type=str, help="checkpoint number (checkpoints/iter_<n>), best or final"
    )
    parser.add_argument(
        "--run", type=str, help="the algorithm trained (checked against the run's config)"
    )
    parser.add_argument("--num_rollouts", type=int, default=1, help="rollouts to replay")
    parser.add_argument(
        "--gen_emission", action="store_true", help="also write Flow's emission CSV per rollout"
    )
    parser.add_argument(
        "--evaluate", action="store_true", help="use the env's evaluation reward (env.evaluate)"
    )
    parser.add_argument(
        "--render_mode", type=str, default="sumo_gui", choices=RENDER_MODES,
        help="accepted for Flow's scripts; rollouts are logged to MCAP (flowrun replay LOG)",
    )  # fmt: skip
    parser.add_argument(
        "--save_render", action="store_true",
        help="accepted for Flow's scripts; render a video from the log with flowrun replay",
    )  # fmt: skip
    parser.add_argument("--horizon", type=int, help="RL steps per rollout (default: the run's)")
    return parser


def checkpoint_arg(checkpoint_num: str) -> str:
    """Flow's checkpoint number as a flowrun checkpoint: ``2`` -> ``checkpoints/iter_000002``;
    ``best``, ``final`` and folders pass through."""
    text = str(checkpoint_num).strip()
    return f"checkpoints/iter_{int(text):06d}" if text.isdigit() else text


def visualizer_rllib(args: argparse.Namespace) -> EvalResult:
    """Replay ``args.num_rollouts`` rollouts of the checkpoint and print Flow's summary.

    Returns:
        the evaluation (returns, speeds and MCAP logs of the policy and of the baseline).

    Raises:
        TrainingError: not an RLlib run, no such checkpoint, or ``--run`` differs from the
            algorithm the run trained.
        ConfigError: ``--num_rollouts`` < 1 or ``--horizon`` < 1.
    """
    from flowrun.training.rllib import evaluate_rllib, is_rllib_run

    run_dir = Path(args.result_dir)
    if not is_rllib_run(run_dir):
        raise TrainingError(f"{run_dir} holds no RLlib checkpoint; train with train.backend: rllib")
    overrides = _overrides(args)
    trained = getattr(eval_config(run_dir).train, "algorithm", None)
    if args.run and trained and args.run.upper() != trained.upper():
        raise TrainingError(
            f"--run {args.run} differs from the algorithm the run trained ({trained}); "
            "drop --run or pass the run's algorithm"
        )
    result = evaluate_rllib(
        run_dir, episodes=args.num_rollouts, overrides=overrides,
        model=checkpoint_arg(args.checkpoint_num),
    )  # fmt: skip
    if args.gen_emission:
        _write_emission(run_dir, result, overrides)
    _print_summary(result)
    return result


def _overrides(args: argparse.Namespace) -> list[str]:
    from flowrun.errors import ConfigError

    overrides = []
    if args.horizon is not None:
        if args.horizon < 1:
            raise ConfigError(f"--horizon must be >= 1, got {args.horizon}")
        overrides.append(f"env.horizon={int(args.horizon)}")
    if args.evaluate:
        overrides.append("env.evaluate=true")
    return overrides


def emission_files(result: EvalResult) -> list[Path]:
    """Where ``--gen_emission`` writes the policy rollouts' CSVs: ``policy_<i>_emission.csv``
    beside each log."""
    return [
        p.with_name(p.stem + "_emission.csv") for p in result.logs if p.stem.startswith("policy")
    ]


def _write_emission(run_dir: Path, result: EvalResult, overrides: Sequence[str]) -> None:
    from flowrun.experiment.emission import flow_emission_csv

    sim_step = eval_config(run_dir, overrides).sim.sim_step
    logs = [p for p in result.logs if p.stem.startswith("policy")]
    for log, out in zip(logs, emission_files(result), strict=True):
        flow_emission_csv(log, out, sim_step)
        print(f"emission file: {out}")


def _print_summary(result: EvalResult) -> None:
    returns = [m.episode_return for m in result.policy]
    speeds = [m.mean_speed for m in result.policy]
    for i, ret in enumerate(returns):
        print(f"Round {i}, return: {ret}")
    print(f"Average, std returns: {np.mean(returns)}, {np.std(returns)}")
    print(f"Average, std speeds: {np.mean(speeds)}, {np.std(speeds)}")
    print(f"rollouts logged to {result.out_dir} (view: flowrun replay <log>)")


__all__ = ["checkpoint_arg", "create_parser", "visualizer_rllib"]
