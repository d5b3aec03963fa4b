"""``flowrun train`` and ``flowrun eval``: stable-baselines3 training and policy evaluation."""

from __future__ import annotations

import sys
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from flowrun.cli.commands_run import (
    AnyConfigArg,
    OutOpt,
    SeedOpt,
    SetOpt,
    console,
    overrides_with_seed,
)
from flowrun.cli.common import DEFAULT_OUT, guarded, on_stop_signals, out_option
from flowrun.cli.feedback import Feedback, duration
from flowrun.cli.tables import compare_table
from flowrun.errors import FlowrunError

if TYPE_CHECKING:
    from flowrun.config.model import ExperimentConfig
    from flowrun.experiment.metrics import RunMetrics
    from flowrun.rundir.train_state import StopRequest
    from flowrun.training.evaluate import EvalResult
    from flowrun.training.trainer import TrainResult

RunDirArg = Annotated[
    Path, typer.Argument(help="A train run folder.", metavar="RUN_DIR", show_default=False)
]
BudgetOpt = Annotated[
    float | None,
    typer.Option(
        "--budget",
        metavar="MINUTES",
        help="Wall time the training may take. Before it starts, an estimate (one "
        "episode of one env for its speed, times the cores training uses and the share of it "
        "training reaches, plus the evaluation episodes) refuses a recipe that would not "
        "fit and says how to fit it; an estimate, not a promise, so training also stops "
        "when the time is up (a complete run with fewer steps; metrics.json says "
        "stopped_at_budget). stable-baselines3 only.",
        show_default=False,
    ),
]
DeadlineOpt = Annotated[
    str | None,
    # flowrun benchmark --budget passes its trainings the end of its budget this way
    typer.Option("--deadline", hidden=True, help="Stop training at this ISO 8601 time."),
]
EvalOutOpt = Annotated[
    Path | None,
    out_option("the evaluation folders, OUT/<timestamp>-<seed>/ (default OUT: RUN_DIR/eval)"),
]


@contextmanager
def stop_on_signals() -> Iterator[StopRequest]:
    """Turn SIGINT and SIGTERM into a :class:`StopRequest` (restored on exit).

    Nothing is raised from inside the handler for the first signal: an exception there could
    land anywhere (half a log chunk written, a pipe to an env process half read).
    """
    from flowrun.rundir.train_state import StopRequest

    request = StopRequest()

    def handler(signum: int, frame: Any) -> None:
        request.signal(signum)

    with on_stop_signals(handler):
        yield request


@guarded
def train(
    config: AnyConfigArg,
    set_: SetOpt = None,
    seed: SeedOpt = None,
    out: OutOpt = DEFAULT_OUT,
    resume: Annotated[
        Path | None,
        typer.Option(
            "--resume",
            metavar="RUN_DIR",
            help="Continue this run folder from its last checkpoint."),
    ] = None,
    ray_address: Annotated[
        str | None,
        typer.Option(
            "--ray-address",
            metavar="ADDRESS",
            help="Ray cluster for train.backend: rllib (default: $RAY_ADDRESS, else a local Ray).",
        ),
    ] = None,
    budget: BudgetOpt = None,
    deadline: DeadlineOpt = None,
) -> None:
    """Train the config's policy (train: section) with stable-baselines3 (or RLlib with
    train.backend: rllib), then evaluate it.

    CONFIG is a YAML file or a Flow config module (a .py file defining flow_params; without
    a train: section it trains PPO with flowrun's defaults). With --resume, the run folder's
    saved config is used (plus --set, e.g. a larger train.total_timesteps) and training
    continues from its last checkpoint, keeping the earlier monitor files, evaluations and
    best model. Ctrl-C or SIGTERM saves a checkpoint and exits with 130 / 143.
    --budget MINUTES estimates the wall time first and refuses what would not fit.
    """
    from flowrun.preflight.budget import PROBE_TEXT, parse_deadline, train_budget
    from flowrun.preflight.prepare import prepare_training

    overrides = overrides_with_seed(set_, seed)
    if seed is not None:
        overrides.append(f"train.seed={seed}")
    plan = prepare_training(config, overrides, resume, out != DEFAULT_OUT, ray_address)
    feedback = Feedback(console)
    for note in plan.notes:
        feedback.phase(note)
    stop_at = parse_deadline(deadline) if deadline is not None else None
    if budget is not None:
        feedback.phase(f"estimating the wall time: {PROBE_TEXT}")
        fits = train_budget(plan.cfg, budget, resume)
        feedback.phase(fits.describe())
        stop_at = fits.deadline
    feedback.phase(_start_phase(plan.cfg, plan.rllib))
    cfg, rllib, train_cfg = plan.cfg, plan.rllib, plan.train
    result = _train_with_progress(feedback, cfg, out, resume, rllib, ray_address, config,
                                  stop_at)  # fmt: skip
    feedback.phase(_finished_phase(result))
    episodes = train_cfg.eval_episodes
    feedback.phase(
        f"final evaluation: the trained model (best, else final) and its baseline, "
        f"{episodes} episode(s) each, recorded"
    )
    shown = _evaluate_and_show(result.run_dir, episodes, True, [], None, "best", None, feedback)
    feedback.close(f"run folder: {result.run_dir}; evaluation folder: {shown}")


def _finished_phase(result: TrainResult) -> str:
    """What training did: steps, time, speed and the evaluations' share."""
    resumed = f" (resumed at {result.resumed_from})" if result.resumed_from else ""

    timing = result.timing
    share = (
        f", evaluation {timing.evaluation_share:.0%} of it"
        if timing is not None and timing.evaluation_share > 0
        else ""
    )
    return (
        f"training {'stopped at the --budget' if result.stopped_at_budget else 'finished'}: "
        f"{result.timesteps} steps{resumed} in {duration(result.wall_clock)}"
        f" ({result.steps_per_second:.0f} steps/s{share})"
    )


def _start_phase(cfg: ExperimentConfig, rllib: bool) -> str:
    """The line said while the environments and the model start (a silent minute else)."""
    from flowrun.config.model import TrainConfig

    train = cfg.train or TrainConfig()
    if rllib:
        return "starting Ray and its environment runners (RLlib)"
    if cfg.sim.backend == "numpy":
        return f"starting {train.n_envs} numpy rings and the {train.algorithm} model"
    return f"starting {train.n_envs} environment process(es) and the {train.algorithm} model"


def _train_with_progress(
    feedback: Feedback,
    cfg: ExperimentConfig,
    out: Path,
    resume: Path | None,
    rllib: bool,
    ray_address: str | None,
    config: Path,
    deadline: float | None = None,
) -> TrainResult:
    """Run the training with its progress display; exit 130/143 when interrupted."""
    from flowrun.training.trainer import train as run_training

    columns = (TextColumn("training"), BarColumn(), MofNCompleteColumn(),
               TextColumn("mean reward {task.fields[reward]}"), TimeElapsedColumn(),
               TimeRemainingColumn())  # fmt: skip
    started = [False]

    def describe(fields: Mapping[str, Any]) -> str:
        return f"training, mean episode reward {fields['reward']}"

    with (
        feedback.progress(columns, describe, None, reward="-") as update,
        stop_on_signals() as stop,
    ):

        def progress(done: int, total: int, reward: float | None) -> None:
            if not started[0]:
                started[0] = True
                feedback.phase(f"training for {total} steps")
            update(completed=done, total=total, reward="-" if reward is None else f"{reward:.1f}")

        try:
            if rllib:
                from flowrun.training.rllib import train_rllib

                result = train_rllib(cfg, out=out, resume_dir=resume, progress=progress,
                                     argv=sys.argv, should_stop=stop, ray_address=ray_address)
            else:
                result = run_training(cfg, out=out, resume_dir=resume, progress=progress,
                                      argv=sys.argv, should_stop=stop, deadline=deadline)
        except KeyboardInterrupt:
            console.print("[yellow]interrupted[/]: checkpoint saved; continue with --resume")
            raise typer.Exit(code=stop.exit_code) from None
    if result.status != "complete" or stop():
        console.print(f"[yellow]interrupted[/] at {result.timesteps} steps: checkpoint saved; "
                      f"continue with: flowrun train {config} --resume {result.run_dir}")
        raise typer.Exit(code=stop.exit_code)
    return result


@guarded
def eval_(
    run_dir: RunDirArg,
    episodes: Annotated[int, typer.Option(
        "--episodes",
        metavar="N",
        help="Episodes of each rollout.")] = 1,
    deterministic: Annotated[
        bool, typer.Option("--deterministic/--stochastic", help="Mean action or sampled action.")
    ] = True,
    set_: SetOpt = None,
    config: Annotated[
        Path | None,
        typer.Option(
            "--config",
            metavar="FILE",
            help="YAML whose sections override the run's config."),
    ] = None,
    model: Annotated[
        str,
        typer.Option(
            "--model",
            metavar="best|final|DIR",
            help="best (falls back to final), final, or (RLlib) a checkpoint folder such as "
            "checkpoints/iter_000004.",
        ),
    ] = "best",
    seed: SeedOpt = None,
    out: EvalOutOpt = None,
) -> None:
    """Roll out a trained policy beside its baseline: for Flow's benchmarks the benchmark's
    own (as flowrun benchmark runs it: SUMO's actuated lights for the grids, human drivers
    for the others), else the all-human version of the same config.

    Episode i of both resets with seed sim.seed + i (--seed S sets sim.seed). The evaluation
    folder (config, metrics.json, MCAP logs) is RUN_DIR/eval/<timestamp>-<seed>/ or, with
    --out DIR, DIR/<timestamp>-<seed>/. Ctrl-C or SIGTERM finishes the logs and exits 130 / 143.
    """
    from flowrun.training.deps import require
    from flowrun.training.rllib import is_rllib_run

    if not is_rllib_run(run_dir):
        require("stable_baselines3")
    feedback = Feedback(console)
    shown = _evaluate_and_show(run_dir, episodes, deterministic, overrides_with_seed(set_, seed),
                               config, model, out, feedback)  # fmt: skip
    feedback.close(f"evaluation folder: {shown}")


def _evaluate_and_show(
    run_dir: Path,
    episodes: int,
    deterministic: bool,
    overrides: list[str],
    config: Path | None,
    model: str,
    out: Path | None,
    feedback: Feedback,
) -> Path:
    """Roll out the policy and its baseline, print their table; the evaluation folder."""
    from flowrun.preflight.prepare import not_a_training_run
    from flowrun.rundir.train_state import run_state
    from flowrun.training.evaluate import eval_config, evaluate, model_path
    from flowrun.training.rllib import evaluate_rllib, is_rllib_run

    evaluate_run = evaluate_rllib if is_rllib_run(run_dir) else evaluate

    run_cfg = eval_config(run_dir, overrides, config)
    if run_cfg.train is None:
        raise not_a_training_run(run_dir)
    if evaluate_run is evaluate:
        model_path(run_dir, model)  # no model: say so before any note about the run
    horizon = run_cfg.env.horizon
    _note_unfinished(run_dir, run_state(run_dir))
    columns = (TextColumn("{task.fields[label]} episode {task.fields[episode]}"), BarColumn(),
               MofNCompleteColumn(), TimeRemainingColumn())  # fmt: skip

    def describe(fields: Mapping[str, Any]) -> str:
        return f"evaluating: {fields['label']} episode {fields['episode']}"

    # Stop at a step boundary so the MCAP log being written is finished cleanly.
    steps = int(horizon)
    with (
        feedback.progress(columns, describe, 2 * episodes * steps, label="policy", episode=0)
        as update,
        stop_on_signals() as stop,
    ):

        def progress(label: str, episode: int, step: int) -> None:
            before = (0 if label == "policy" else episodes) + episode
            update(completed=before * steps + step, label=label, episode=episode)
            stop.check()

        try:
            result = evaluate_run(run_dir, episodes, deterministic, overrides, config, model,
                                  progress, out, should_stop=stop)
        except KeyboardInterrupt:
            console.print("[yellow]interrupted[/]: evaluation logs finished")
            raise typer.Exit(code=stop.exit_code) from None
        except FlowrunError:
            if not stop():
                raise
            # the signal also stopped a child process (netconvert): still an interruption
            console.print("[yellow]interrupted[/]: evaluation logs finished")
            raise typer.Exit(code=stop.exit_code) from None
    _show(result, f"{run_dir.name}: {result.model.name}, {episodes} episode(s)",
          run_cfg.env.evaluate)  # fmt: skip
    return Path(result.out_dir)


def _show(result: EvalResult, title: str, evaluate_mode: bool) -> None:
    """The policy-vs-baseline table, and which baseline it is."""
    compared = result.comparison
    label = "all-human" if compared is None else compared.label
    console.print(compare_table(title, _rows(result.policy), _rows(result.baseline), label))
    if compared is None:
        console.print("no all-human baseline: every vehicle group is RL (no human to copy)")
    elif compared.benchmark is not None:
        console.print(f"baseline row: {compared.description}")
        if not evaluate_mode:
            console.print("[yellow]note[/]: the baseline runs in evaluate mode, as the "
                          "benchmark's; --set env.evaluate=true scores the policy the same way")


def _note_unfinished(run_dir: Path, state: str) -> None:
    """Say so when the evaluated run did not finish training."""
    if state == "complete":
        return
    what = {"running": "is still training", "cut": "was cut off (killed while training)",
            "interrupted": "was interrupted", "failed": "failed"}[state]  # fmt: skip
    console.print(f"[yellow]note[/]: {run_dir} {what}; evaluating its saved model anyway "
                  f"(metrics.json records run_status: {state})")  # fmt: skip


def _rows(runs: list[RunMetrics]) -> list[dict[str, Any]]:
    """Each episode's metrics, then their mean when there are several."""
    from flowrun.training.evaluate import mean_metrics

    rows: list[dict[str, Any]] = [m.to_dict() for m in runs]
    return [*rows, {**mean_metrics(runs), "run": "mean"}] if len(runs) > 1 else rows


def register(app: typer.Typer) -> None:
    """Add the training commands to the app."""
    app.command("train")(train)
    app.command("eval")(eval_)
