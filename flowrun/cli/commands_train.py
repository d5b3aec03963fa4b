"""``flowrun train`` and ``flowrun eval``: stable-baselines3 training and policy evaluation."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table

from flowrun.cli.commands_run import (
    AnyConfigArg,
    OutOpt,
    SeedOpt,
    SetOpt,
    console,
    overrides_with_seed,
)
from flowrun.cli.common import DEFAULT_OUT, guarded, load_located, on_stop_signals, out_option
from flowrun.errors import FlowrunError

if TYPE_CHECKING:
    from flowrun.experiment.metrics import RunMetrics
    from flowrun.rundir.train_state import StopRequest

RunDirArg = Annotated[Path, typer.Argument(help="A train run folder.", show_default=False)]
EvalOutOpt = Annotated[
    Path | None,
    out_option("the evaluation folders, OUT/<timestamp>-<seed>/ (default OUT: RUN_DIR/eval)"),
]


def not_a_training_run(run_dir: Path) -> FlowrunError:
    """The error for a run folder whose config has no ``train:`` section (a baseline run)."""
    return FlowrunError(
        f"{run_dir} is not a training run: its config.yaml has no train: section (a "
        "baseline run folder?); pass a folder made by flowrun train"
    )


def _check_steps_left(run_dir: Path, total: int) -> None:
    """Refuse to resume a complete run that has already trained ``total`` steps (it would
    train nothing and replace its final model and evaluation)."""
    from flowrun.rundir.train_state import read_metrics, run_state

    done = (read_metrics(run_dir) or {}).get("timesteps")
    if run_state(run_dir) == "complete" and isinstance(done, int) and done >= total:
        raise FlowrunError(
            f"{run_dir} already trained {done} of train.total_timesteps={total} steps; to "
            f"continue, raise it (--set train.total_timesteps={2 * done}), or evaluate it "
            f"with flowrun eval {run_dir}"
        )


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


def _progress_bar(*columns: Any) -> Progress:
    return Progress(*columns, console=console, transient=True, disable=not sys.stderr.isatty())


@guarded
def train(
    config: AnyConfigArg,
    set_: SetOpt = None,
    seed: SeedOpt = None,
    out: OutOpt = DEFAULT_OUT,
    resume: Annotated[
        Path | None,
        typer.Option("--resume", help="Continue this run folder from its last checkpoint."),
    ] = None,
    ray_address: Annotated[
        str | None,
        typer.Option(
            "--ray-address",
            help="Ray cluster for train.backend: rllib (default: $RAY_ADDRESS, else a local Ray).",
        ),
    ] = None,
) -> None:
    """Train the config's policy (train: section) with stable-baselines3 (or RLlib with
    train.backend: rllib), then evaluate it.

    CONFIG is a YAML file or a Flow config module (a .py file defining flow_params; without
    a train: section it trains PPO with flowrun's defaults). With --resume, the run folder's
    saved config is used (plus --set, e.g. a larger train.total_timesteps) and training
    continues from its last checkpoint, keeping the earlier monitor files, evaluations and
    best model. Ctrl-C or SIGTERM saves a checkpoint and exits with 130 / 143.
    """
    from flowrun.config.flow_module import is_flow_module
    from flowrun.config.loader import load_config
    from flowrun.config.model import TrainConfig
    from flowrun.config.preflight import preflight
    from flowrun.training.deps import require
    from flowrun.training.trainer import resume_config
    from flowrun.training.trainer import train as run_training

    overrides = overrides_with_seed(set_, seed)
    if seed is not None:
        overrides.append(f"train.seed={seed}")
    if resume is not None and out != DEFAULT_OUT:
        raise FlowrunError(
            f"--out has no effect with --resume: training continues in {resume}; drop --out"
        )
    if resume is not None:
        saved = resume / "config.yaml"
        if saved.is_file() and load_config(saved).train is None:
            raise not_a_training_run(resume)
        cfg = resume_config(resume, overrides)
        _check_steps_left(resume, cfg.train.total_timesteps if cfg.train else 0)
        console.print(f"resuming {resume} with its config.yaml (CONFIG is not re-read)")
    else:
        cfg, where = load_located(config, overrides)
        if cfg.train is None and is_flow_module(config):
            cfg = replace(cfg, train=TrainConfig())
            console.print(
                "a Flow config has no train: section: training PPO with flowrun's defaults "
                "(change them with --set train.total_timesteps=... etc.)"
            )
        preflight(cfg, where)  # env class, its params, hyper-parameter names: at file:line
    rllib = cfg.train is not None and cfg.train.backend == "rllib"
    if rllib:
        from flowrun.training.rllib import require_ray, train_rllib

        require_ray()
    else:
        require("stable_baselines3")
        if ray_address is not None:
            raise FlowrunError(
                "--ray-address is for train.backend: rllib; this config trains with "
                "stable-baselines3 (set train.backend: rllib, or drop --ray-address)"
            )
    columns = (TextColumn("training"), BarColumn(), MofNCompleteColumn(),
               TextColumn("mean reward {task.fields[reward]}"), TimeElapsedColumn(),
               TimeRemainingColumn())
    with _progress_bar(*columns) as bar, stop_on_signals() as stop:
        task = bar.add_task("train", total=None, reward="-")

        def progress(done: int, total: int, reward: float | None) -> None:
            shown = "-" if reward is None else f"{reward:.1f}"
            bar.update(task, completed=done, total=total, reward=shown)

        try:
            if rllib:
                result = train_rllib(cfg, out=out, resume_dir=resume, progress=progress,
                                     argv=sys.argv, should_stop=stop, ray_address=ray_address)
            else:
                result = run_training(cfg, out=out, resume_dir=resume, progress=progress,
                                      argv=sys.argv, should_stop=stop)
        except KeyboardInterrupt:
            console.print("[yellow]interrupted[/]: checkpoint saved; continue with --resume")
            raise typer.Exit(code=stop.exit_code) from None
    resumed = f" (resumed at {result.resumed_from})" if result.resumed_from else ""
    if result.status != "complete" or stop():
        console.print(f"[yellow]interrupted[/] at {result.timesteps} steps: checkpoint saved; "
                      f"continue with: flowrun train {config} --resume {result.run_dir}")
        raise typer.Exit(code=stop.exit_code)
    timing = result.timing
    share = f", evaluation {timing.evaluation_share:.0%} of it" if timing is not None else ""
    console.print(f"trained to {result.timesteps} steps{resumed} in {result.wall_clock:.0f} s "
                  f"({result.steps_per_second:.0f} steps/s{share}); run folder: {result.run_dir}")
    episodes = cfg.train.eval_episodes if cfg.train is not None else 1
    _evaluate_and_show(result.run_dir, episodes, True, [], None, "best", None)


@guarded
def eval_(
    run_dir: RunDirArg,
    episodes: Annotated[int, typer.Option("--episodes", help="Episodes of each rollout.")] = 1,
    deterministic: Annotated[
        bool, typer.Option("--deterministic/--stochastic", help="Mean action or sampled action.")
    ] = True,
    set_: SetOpt = None,
    config: Annotated[
        Path | None,
        typer.Option("--config", help="YAML whose sections override the run's config."),
    ] = None,
    model: Annotated[
        str,
        typer.Option(
            "--model",
            help="best (falls back to final), final, or (RLlib) a checkpoint folder such as "
            "checkpoints/iter_000004.",
        ),
    ] = "best",
    seed: SeedOpt = None,
    out: EvalOutOpt = None,
) -> None:
    """Roll out a trained policy beside the all-human baseline of the same config.

    Episode i of both resets with seed sim.seed + i (--seed S sets sim.seed). The evaluation
    folder (config, metrics.json, MCAP logs) is RUN_DIR/eval/<timestamp>-<seed>/ or, with
    --out DIR, DIR/<timestamp>-<seed>/. Ctrl-C or SIGTERM finishes the logs and exits 130 / 143.
    """
    from flowrun.training.deps import require
    from flowrun.training.rllib import is_rllib_run

    if not is_rllib_run(run_dir):
        require("stable_baselines3")
    _evaluate_and_show(run_dir, episodes, deterministic, overrides_with_seed(set_, seed),
                       config, model, out)


def _evaluate_and_show(
    run_dir: Path,
    episodes: int,
    deterministic: bool,
    overrides: list[str],
    config: Path | None,
    model: str,
    out: Path | None,
) -> None:
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
    state = run_state(run_dir)
    if state != "complete":
        what = {"running": "is still training", "cut": "was cut off (killed while training)",
                "interrupted": "was interrupted", "failed": "failed"}[state]
        console.print(f"[yellow]note[/]: {run_dir} {what}; evaluating its saved model anyway "
                      f"(metrics.json records run_status: {state})")
    columns = (TextColumn("{task.fields[label]} episode {task.fields[episode]}"), BarColumn(),
               MofNCompleteColumn(), TimeRemainingColumn())
    # Stop at a step boundary so the MCAP log being written is finished cleanly.
    with _progress_bar(*columns) as bar, stop_on_signals() as stop:
        task = bar.add_task("eval", total=int(horizon), label="policy", episode=0)

        def progress(label: str, episode: int, step: int) -> None:
            bar.update(task, completed=step, label=label, episode=episode)
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
    console.print(compare_table(f"{run_dir.name}: {result.model.name}, {episodes} episode(s)",
                                result.policy, result.baseline))
    console.print(f"evaluation folder: {result.out_dir}")


def compare_table(title: str, policy: list[RunMetrics], baseline: list[RunMetrics]) -> Table:
    """Policy vs all-human baseline, one row per episode each, then the means."""
    from flowrun.training.evaluate import mean_metrics

    table = Table(title=title, caption="speeds in m/s; std: across cars, averaged over steps")
    for col in ("rollout", "episode", "mean speed", "last-half mean speed", "speed std",
                "last-half speed std", "min speed", "return", "collisions"):
        table.add_column(col, justify="right")
    for label, rows in (("policy", policy), ("all-human", baseline)):
        for m in rows:
            table.add_row(label, str(m.run), *_cells(m.to_dict()))
        if len(rows) > 1:
            table.add_row(label, "mean", *_cells(mean_metrics(rows)))
    return table


def _cells(m: dict[str, Any]) -> list[str]:
    speeds = ("mean_speed", "last_half_mean_speed", "speed_std", "last_half_speed_std",
              "min_speed")
    return [*(f"{m[k]:.3f}" for k in speeds), f"{m['episode_return']:.1f}",
            f"{m['collisions']:g}"]


def register(app: typer.Typer) -> None:
    """Add the training commands to the app."""
    app.command("train")(train)
    app.command("eval")(eval_)
