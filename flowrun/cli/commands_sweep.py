"""``flowrun sweep``: a baseline per point of a grid of config values, in parallel processes.

Each point runs as its own ``flowrun baseline`` process (libsumo runs one simulation per
process), in its own session, so a Ctrl-C reaches the sweep only; the sweep then passes the
signal on once to each running point, which finishes its log and labels its folder
``interrupted``, and exits 130 (SIGINT) or 143 (SIGTERM). Finished points are kept; the same
command again skips them.

With ``--backend ray`` (or ``--ray-address``) the same commands run as Ray tasks on a Ray
cluster (:mod:`flowrun.experiment.sweep_ray`), with the same folders, table and stopping.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from flowrun.cli.commands_run import console
from flowrun.cli.common import (
    DEFAULT_OUT,
    AnyConfigArg,
    NoRecordOpt,
    OutOpt,
    SeedOpt,
    SetOpt,
    StepsOpt,
    guarded,
    interrupted_exit,
    overrides_with_seed,
)
from flowrun.cli.feedback import Feedback
from flowrun.cli.points import STOP_GRACE_S, describe_points, run_points, stop_requests
from flowrun.errors import ConfigError, FlowrunError
from flowrun.experiment.sweep import SweepPlan, SweepPoint
from flowrun.experiment.sweep_ray import NOT_STARTED
from flowrun.rundir.folders import Interrupted

#: How a sweep runs its points: ``local`` processes, or ``ray`` tasks.
BACKENDS = ("local", "ray")
#: Called as each point ends: ``(point, exit code, last stderr line)``.
OnDone = Callable[[SweepPoint, int, str], None]
#: Runs the points: ``(commands, jobs, on_done)``, like :func:`run_points`.
Runner = Callable[[list[tuple[SweepPoint, list[str]]], int, OnDone], None]

def point_command(
    config: Path,
    sets: list[str],
    plan: SweepPlan,
    point: SweepPoint,
    out: Path,
    run_args: list[str],
) -> list[str]:
    """The ``flowrun baseline`` command of one point."""
    cmd = [sys.executable, "-m", "flowrun.cli.main", "baseline", str(config)]
    for item in [*sets, *point.overrides]:
        cmd += ["--set", item]
    cmd += ["--seed", str(point.seed), "--out", str(out)]
    return [*cmd, "--folder", str(plan.folder / point.label), *run_args]


def _check_points(config: Path, sets: list[str], plan: SweepPlan, steps: int | None) -> None:
    """Load every grid point's config (and its step count) before anything runs."""
    from flowrun.cli.commands_run import checked_baseline_config
    from flowrun.experiment.baseline import resolve_steps

    seen: set[tuple[tuple[str, str], ...]] = set()
    for point in plan.points:
        if point.values in seen:
            continue
        seen.add(point.values)
        try:
            overrides = [*sets, *point.overrides]
            resolve_steps(checked_baseline_config(config, overrides, "flowrun sweep"), steps)
        except ConfigError as err:
            where = ", ".join(point.overrides)
            raise ConfigError(f"with --grid {where}: {err}") from None


def results_table(plan: SweepPlan, rows: list[dict[str, Any]], metric: str) -> Table:
    """One row per point: swept values, seed, status, the metric and the mean speed."""
    table = Table(title=f"sweep: {len(rows)} point(s), {plan.folder}")
    keys = [a.key for a in plan.axes]
    shown = [*keys, "seed", "status", metric] + (["mean_speed"] if metric != "mean_speed" else [])
    for col in shown:
        table.add_column(col, justify="right")
    for row in rows:
        cells = []
        for col in shown:
            value = row.get(col)
            cells.append(f"{value:.4g}" if isinstance(value, float) else _text(value))
        table.add_row(*cells)
    return table


@guarded
def sweep(
    config: AnyConfigArg,
    grid: Annotated[
        list[str],
        typer.Option(
            "--grid",
            metavar="KEY=V1,V2,...",
            help="key.path=v1,v2,... : the values to sweep (YAML scalars). Several multiply.",
        ),
    ],
    seeds: Annotated[
        int, typer.Option("--seeds", metavar="N", help="Seeds per grid point.")
    ] = 1,
    jobs: Annotated[
        int | None,
        typer.Option(
            "--jobs",
            metavar="N",
            help="Points run at once (default: CPU count; on Ray: the cluster's CPUs)."
        ),
    ] = None,
    metric: Annotated[
        str, typer.Option(
            "--metric",
            metavar="NAME",
            help="Metric plotted against the first --grid key.")
    ] = "mean_speed",
    steps: StepsOpt = None,
    runs: Annotated[int, typer.Option("--runs", metavar="N", help="Runs per point.")] = 1,
    no_record: NoRecordOpt = False,
    backend: Annotated[
        str | None,
        typer.Option(
            "--backend",
            metavar="local|ray",
            help="local: processes on this machine; ray: Ray tasks on a Ray cluster "
            "(default: local; ray with --ray-address).",
        ),
    ] = None,
    ray_address: Annotated[
        str | None,
        typer.Option(
            "--ray-address",
            metavar="ADDRESS",
            help="Ray cluster to run the points on; implies --backend ray (default with "
            "--backend ray: $RAY_ADDRESS, else a local Ray for the sweep).",
        ),
    ] = None,
    seed: SeedOpt = None,
    set_: SetOpt = None,
    out: OutOpt = DEFAULT_OUT,
) -> None:
    """Run a baseline for every combination of --grid values (x --seeds), in parallel.

    Each point is a run folder in OUT/<name>/sweep-<id>/, named after its values.

    Then results.csv, results.md and <metric>.png (mean and std over seeds vs the first key).

    Ctrl-C/SIGTERM keeps finished points (exit 130/143); the same command runs only the rest.

    With --backend ray (or --ray-address) each point is a Ray task (one CPU, its own SUMO
    process); on several machines the config and --out must be on a shared file system.
    """
    from flowrun.experiment import sweep as sw

    sets = list(set_ or [])
    request = SweepRequest(config, grid, seeds, jobs, metric, steps, runs, no_record, backend,
                           ray_address, seed, sets, out)  # fmt: skip
    plan, chosen, run_args = prepare_sweep(request)
    try:
        with _cluster(chosen, ray_address) as cpus, sw.locked(plan):
            sw.write_plan(plan, sys.argv)
            runner = _ray_runner(chosen)
            _run_sweep(config, sets, plan, out, run_args, jobs or cpus, metric, runner)
    except OSError as err:
        raise FlowrunError(f"cannot write sweep folder {plan.folder}: {err.strerror}") from None


@dataclass(frozen=True)
class SweepRequest:
    """``flowrun sweep``'s arguments (see its help)."""

    config: Path
    grid: list[str]
    seeds: int = 1
    jobs: int | None = None
    metric: str = "mean_speed"
    steps: int | None = None
    runs: int = 1
    no_record: bool = False
    backend: str | None = None
    ray_address: str | None = None
    seed: int | None = None
    sets: list[str] = field(default_factory=list)
    out: Path = DEFAULT_OUT


def prepare_sweep(request: SweepRequest) -> tuple[SweepPlan, str, list[str]]:
    """Every check a sweep makes before it starts, and its plan: the points, the backend
    (``local`` or ``ray``) and the arguments each point's ``flowrun baseline`` gets.

    Raises:
        ConfigError: a bad --grid, metric, number or config, or a point whose config does
            not load (with its values).
        FlowrunError: an unusable --out, a backend that cannot run.
    """
    from flowrun.cli.commands_run import checked_baseline_config
    from flowrun.experiment import sweep as sw
    from flowrun.rundir.folders import check_out_dir

    r = request
    axes = sw.parse_grid(r.grid)
    sw.check_metric(r.metric, has_signals=True)
    if r.jobs is not None and r.jobs < 1:
        raise ConfigError(f"--jobs must be >= 1, got {r.jobs}")
    if r.runs < 1:
        raise ConfigError(f"--runs must be >= 1, got {r.runs}")
    chosen = _backend(r.backend, r.ray_address)
    overrides = overrides_with_seed(r.sets, r.seed)
    cfg = checked_baseline_config(r.config, overrides, "flowrun sweep")
    run_args = [*(["--steps", str(r.steps)] if r.steps is not None else []), "--runs", str(r.runs)]
    run_args += ["--no-record"] if r.no_record else []
    plan = sw.plan_sweep(cfg, axes, r.seeds, r.out, run_args)
    _check_points(r.config, r.sets, plan, r.steps)
    check_out_dir(r.out)
    return plan, chosen, run_args


def _run_sweep(
    config: Path,
    sets: list[str],
    plan: SweepPlan,
    out: Path,
    run_args: list[str],
    jobs: int | None,
    metric: str,
    runner: Runner | None = None,
) -> None:
    """Run the points not done yet (with ``runner``, default :func:`run_points`), then write
    and print the results."""
    from flowrun.experiment import sweep as sw

    todo = [p for p in plan.points if sw.finished_folder(plan, p) is None]
    skipped = len(plan.points) - len(todo)
    if skipped:
        console.print(f"{skipped} of {len(plan.points)} point(s) already done: skipped")
    failures: list[str] = []
    commands = [(p, point_command(config, sets, plan, p, out, run_args)) for p in todo]
    columns = (TextColumn("sweep"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
               TextColumn("{task.fields[last]}"))  # fmt: skip
    done = [skipped]
    feedback = Feedback(console)
    describe = describe_points("sweep")
    with feedback.progress(columns, describe, len(plan.points), last="") as update:
        update(completed=skipped)

        def on_done(point: SweepPoint, code: int, last: str) -> None:
            if code == NOT_STARTED:
                return
            if code != 0:
                failures.append(f"{point.label}: exit {code}: {last}")
            done[0] += 1
            update(completed=done[0], last=point.label)

        try:
            (runner or run_points)(commands, jobs or os.cpu_count() or 1, on_done)
        except KeyboardInterrupt as err:
            _report(plan, metric)
            raise interrupted_exit(
                err, f"finished points kept in {plan.folder}; run the same command to go on"
            ) from None
    _report(plan, metric)
    if failures:
        for line in failures:
            typer.secho(f"failed: {line}", err=True, fg=typer.colors.RED)
        raise FlowrunError(f"{len(failures)} of {len(plan.points)} point(s) failed (above)")


def _backend(backend: str | None, ray_address: str | None) -> str:
    """``local`` or ``ray``: ``--backend``, else ``ray`` when ``--ray-address`` is given.

    Raises:
        ConfigError: an unknown backend, or ``--ray-address`` with ``--backend local``.
    """
    if backend is None:
        return "ray" if ray_address else "local"
    if backend not in BACKENDS:
        from flowrun.suggest import unknown_name

        raise ConfigError(unknown_name("--backend", backend, BACKENDS))
    if backend == "local" and ray_address:
        raise ConfigError(
            "--ray-address runs the points on Ray: drop --backend local, or drop --ray-address"
        )
    return backend


def _cluster(backend: str, address: str | None) -> AbstractContextManager[int | None]:
    """For ``ray``: attach to the cluster (or start a local Ray) for the sweep; yields its
    CPU count (the default --jobs). For ``local``: nothing, yields ``None``."""
    if backend != "ray":
        return nullcontext(None)

    @contextmanager
    def attached() -> Iterator[int | None]:
        from flowrun.training.rllib.cluster import ray_session

        with ray_session(address, purpose="flowrun sweep --backend ray", rllib=False) as session:
            yield max(1, int(session.cpus))

    return attached()


def _ray_runner(backend: str) -> Runner | None:
    """The Ray runner of the points (``None``: local processes)."""
    if backend != "ray":
        return None
    from flowrun.experiment.sweep_ray import run_points_on_ray

    def runner(
        commands: list[tuple[SweepPoint, list[str]]],
        jobs: int,
        on_done: Callable[[SweepPoint, int, str], None],
    ) -> None:
        with stop_requests() as stop:
            run_points_on_ray(commands, jobs, on_done, stop, STOP_GRACE_S)
            if stop:
                raise Interrupted(stop[0])

    return runner


def _report(plan: SweepPlan, metric: str) -> None:
    """Tables and plot of the finished points, printed and written to the sweep folder."""
    from flowrun.experiment import sweep as sw
    from flowrun.experiment import sweep_report

    rows = sw.collect(plan)
    try:
        csv_path, md_path = sweep_report.write_tables(plan, rows, metric)
        plot = sweep_report.plot_metric(plan, rows, metric)
    except OSError as err:
        raise FlowrunError(f"cannot write sweep results in {plan.folder}: {err.strerror}") from None
    console.print(results_table(plan, rows, metric))
    console.print(f"table: {csv_path} and {md_path.name}; plot: {plot.name}")


def register(app: typer.Typer) -> None:
    """Add ``sweep`` to the app."""
    app.command("sweep")(sweep)


def _text(value: Any) -> str:
    return "" if value is None else str(value)
