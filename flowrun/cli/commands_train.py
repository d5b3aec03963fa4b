"""``flowrun train`` and ``flowrun eval``: stable-baselines3 training and policy evaluation."""

from __future__ import annotations

import sys
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
    interrupt_between_steps,
    overrides_with_seed,
    sigterm_as_interrupt,
)
from flowrun.cli.common import guarded

if TYPE_CHECKING:
    from flowrun.experiment.metrics import RunMetrics

RunDirArg = Annotated[Path, typer.Argument(help="A train run folder.", show_default=False)]


def _progress_bar(*columns: Any) -> Progress:
    return Progress(*columns, console=console, transient=True, disable=not sys.stderr.isatty())


@guarded
def train(
    config: AnyConfigArg,
    set_: SetOpt = None,
    seed: SeedOpt = None,
    out: OutOpt = Path("runs"),
    resume: Annotated[
        Path | None,
        typer.Option("--resume", help="Continue this run folder from its last checkpoint."),
    ] = None,
) -> None:
    """Train the config's policy (train: section) with stable-baselines3, then evaluate it.

    CONFIG is a YAML file or a Flow config module (a .py file defining flow_params; without
    a train: section it trains PPO with flowrun's defaults). With --resume, the run folder's
    saved config is used (plus --set, e.g. a larger train.total_timesteps) and training
    continues from its last checkpoint.
    """
    from flowrun.config.flow_module import is_flow_module, load_any_config
    from flowrun.config.model import TrainConfig
    from flowrun.training.deps import require
    from flowrun.training.trainer import resume_config
    from flowrun.training.trainer import train as run_training

    require("stable_baselines3")
    overrides = overrides_with_seed(set_, seed)
    if seed is not None:
        overrides.append(f"train.seed={seed}")
    if resume is not None:
        cfg = resume_config(resume, overrides)
        console.print(f"resuming {resume} with its config.yaml (CONFIG is not re-read)")
    else:
        cfg = load_any_config(config, overrides)
        if cfg.train is None and is_flow_module(config):
            cfg = replace(cfg, train=TrainConfig())
            console.print(
                "a Flow config has no train: section: training PPO with flowrun's defaults "
                "(change them with --set train.total_timesteps=... etc.)"
            )
    columns = (TextColumn("training"), BarColumn(), MofNCompleteColumn(),
               TextColumn("mean reward {task.fields[reward]}"), TimeElapsedColumn(),
               TimeRemainingColumn())
    with _progress_bar(*columns) as bar, sigterm_as_interrupt():
        task = bar.add_task("train", total=None, reward="-")

        def progress(done: int, total: int, reward: float | None) -> None:
            shown = "-" if reward is None else f"{reward:.1f}"
            bar.update(task, completed=done, total=total, reward=shown)

        try:
            result = run_training(cfg, out=out, resume_dir=resume, progress=progress,
                                  argv=sys.argv)
        except KeyboardInterrupt:
            console.print("[yellow]interrupted[/]: checkpoint saved; continue with --resume")
            raise typer.Exit(code=130) from None
    resumed = f" (resumed at {result.resumed_from})" if result.resumed_from else ""
    console.print(f"trained to {result.timesteps} steps{resumed} in {result.wall_clock:.0f} s "
                  f"({result.steps_per_second:.0f} steps/s); run folder: {result.run_dir}")
    episodes = cfg.train.eval_episodes if cfg.train is not None else 1
    _evaluate_and_show(result.run_dir, episodes, True, [], None, "best")


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
        str, typer.Option("--model", help="best (falls back to final) or final.")
    ] = "best",
) -> None:
    """Roll out a trained policy beside the all-human baseline of the same config."""
    from flowrun.training.deps import require

    require("stable_baselines3")
    _evaluate_and_show(run_dir, episodes, deterministic, list(set_ or []), config, model)


def _evaluate_and_show(
    run_dir: Path,
    episodes: int,
    deterministic: bool,
    overrides: list[str],
    config: Path | None,
    model: str,
) -> None:
    from flowrun.training.evaluate import eval_config, evaluate

    horizon = eval_config(run_dir, overrides, config).env.horizon
    columns = (TextColumn("{task.fields[label]} episode {task.fields[episode]}"), BarColumn(),
               MofNCompleteColumn(), TimeRemainingColumn())
    # Stop at a step boundary so the MCAP log being written is finished cleanly.
    with _progress_bar(*columns) as bar, interrupt_between_steps() as check:
        task = bar.add_task("eval", total=int(horizon), label="policy", episode=0)

        def progress(label: str, episode: int, step: int) -> None:
            bar.update(task, completed=step, label=label, episode=episode)
            check()

        try:
            result = evaluate(run_dir, episodes, deterministic, overrides, config, model,
                              progress)
        except KeyboardInterrupt:
            console.print("[yellow]interrupted[/]: evaluation logs finished")
            raise typer.Exit(code=130) from None
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
