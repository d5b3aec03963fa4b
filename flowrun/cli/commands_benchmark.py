"""``flowrun benchmark``: Flow's eleven benchmarks, their baselines over seeds, in one table.

Every baseline run (and, with ``--train``, every training and policy evaluation) is its own
``flowrun`` process, run by the sweep's process pool (:func:`run_points`): a Ctrl-C reaches
this command only, which passes it on once to the running processes, writes the results of
the runs that finished and exits 130 (SIGINT) or 143 (SIGTERM).
"""

from __future__ import annotations

import os
import sys
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from flowrun.cli.commands_run import console
from flowrun.cli.common import (
    DEFAULT_OUT,
    SeedOpt,
    SetOpt,
    guarded,
    interrupted_exit,
    out_option,
)
from flowrun.cli.feedback import Feedback
from flowrun.cli.points import describe_points, run_points
from flowrun.errors import ConfigError, FlowrunError
from flowrun.experiment.benchmark import Benchmark
from flowrun.experiment.benchmark_run import BenchmarkPlan
from flowrun.experiment.sweep import SweepPoint

#: Steps of each run of ``flowrun benchmark`` without names (a quick look).
QUICK_STEPS = 50

NamesArg = Annotated[
    list[str] | None,
    typer.Argument(
        help="Benchmarks: names (figureeight0 ... bottleneck2), families (figureeight, merge, "
        f"grid, bottleneck) or all. Without any: a quick look at all of them, {QUICK_STEPS} "
        "steps each, one seed.",
        metavar="NAME",
        show_default=False,
    ),
]


BenchmarkOutOpt = Annotated[
    Path,
    out_option("a new benchmark folder, OUT/benchmark/<timestamp>/ (results and a run folder "
               "per run)"),
]


def _point(bench: Benchmark, kind: str, seed: int) -> SweepPoint:
    return SweepPoint((("benchmark", bench.name), ("run", kind)), seed)


def _check_configs(plan: BenchmarkPlan) -> None:
    """Load every benchmark's config and its baseline before anything runs; with --train,
    check each recipe as ``flowrun train`` would (its library installed, its options).

    Raises:
        ConfigError: a missing or invalid config, or a --set it refuses (naming the benchmark).
    """
    from flowrun.experiment.baseline import resolve_steps
    from flowrun.loading.loader import load_config
    from flowrun.preflight.prepare import check_recipe

    for bench in plan.benchmarks:
        path = bench.config_path(plan.configs)
        if not path.is_file():
            raise ConfigError(f"benchmark {bench.name}: no config {path}; pass --configs DIR")
        if plan.train:
            check_recipe(path, list(plan.sets))  # its own file:line: no benchmark prefix
        try:
            load_config(path, list(plan.sets))
            resolve_steps(load_config(path, [*plan.sets, *bench.baseline]), None)
        except ConfigError as err:
            raise ConfigError(f"benchmark {bench.name}: {err}") from None


def _first_seed(bench: Benchmark, configs: Path | None, sets: tuple[str, ...]) -> int:
    """The first seed without --seed: ``sim.seed`` of the config (a --set of it counts)."""
    from flowrun.experiment.benchmark import default_config_dir
    from flowrun.loading.loader import load_config

    path = bench.config_path(configs if configs is not None else default_config_dir())
    if not path.is_file():
        return 0  # _check_configs says which file is missing
    try:
        return int(load_config(path, list(sets)).sim.seed or 0)
    except ConfigError as err:
        raise ConfigError(f"benchmark {bench.name}: {err}") from None


def make_plan(
    names: list[str],
    seeds: int,
    jobs: int | None,
    train: bool,
    configs: Path | None,
    record: bool,
    seed: int | None,
    sets: list[str],
    out: Path,
    budget: float | None = None,
) -> BenchmarkPlan:
    """What ``flowrun benchmark`` runs, checked before anything starts. No ``names``: all
    benchmarks for :data:`QUICK_STEPS` steps (a quick look; a ``--set env.horizon`` wins).
    With ``budget`` (minutes), the estimated wall time must fit it.

    Raises:
        ConfigError: an unknown benchmark, a bad number, a config that does not load, a
            ``--train`` recipe whose library is not installed.
        FlowrunError: an unusable ``out``, an estimate over ``budget``.
    """
    from flowrun.experiment import benchmark as bm
    from flowrun.experiment.benchmark_run import folder_name
    from flowrun.rundir.folders import check_out_dir, unique_dir

    if not names:
        sets = [f"env.horizon={QUICK_STEPS}", *sets]
    chosen = bm.select(names or ["all"])
    if seeds < 1:
        raise ConfigError(f"--seeds must be >= 1, got {seeds}")
    if jobs is not None and jobs < 1:
        raise ConfigError(f"--jobs must be >= 1, got {jobs}")
    first = seed if seed is not None else _first_seed(chosen[0], configs, tuple(sets))
    plan = BenchmarkPlan(
        folder=out / "benchmark" / folder_name(),
        benchmarks=tuple(chosen),
        seeds=tuple(range(first, first + seeds)),
        configs=(configs if configs is not None else bm.default_config_dir()).resolve(),
        sets=tuple(sets),
        train=train,
        record=record,
    )
    _check_configs(plan)
    check_out_dir(out)
    if budget is not None:
        plan = _within_budget(plan, budget)
    return replace(plan, folder=unique_dir(plan.folder).resolve())


@guarded
def benchmark(
    names: NamesArg = None,
    seeds: Annotated[int, typer.Option("--seeds", metavar="N",
    help="Seeds per benchmark.")] = 1,
    jobs: Annotated[
        int | None, typer.Option("--jobs", metavar="N",
        help="Runs at once (default: CPU count).")
    ] = None,
    train: Annotated[
        bool,
        typer.Option(
            "--train",
            help="Also train each benchmark's policy (its train: section) once per seed and "
            "score each on 5 evaluation episodes (seeds 1000000-1000004, never used in "
            "training) beside the baseline on the same episodes.",
        ),
    ] = False,
    configs: Annotated[
        Path | None,
        typer.Option(
            "--configs",
            metavar="DIR",
            help="Folder of the benchmark configs (default: configs/benchmarks).",
            show_default=False,
        ),
    ] = None,
    record: Annotated[
        bool, typer.Option("--record", help="Write MCAP logs of the baseline runs.")
    ] = False,
    budget: Annotated[
        float | None,
        typer.Option(
            "--budget",
            metavar="MINUTES",
            help="With --train: the wall time the whole command may take. Before anything "
            "runs, an estimate (one episode of each benchmark's env, times the cores "
            "training uses and the share of it training reaches, plus the baselines and "
            "evaluation episodes) refuses what would not fit and says how to fit it; an "
            "estimate, not a promise, so every training also stops when the time is up (less "
            "the evaluations that follow) and its result file says it stopped at the budget.",
            show_default=False,
        ),
    ] = None,
    seed: SeedOpt = None,
    set_: SetOpt = None,
    out: BenchmarkOutOpt = DEFAULT_OUT,
) -> None:
    """Run Flow's benchmarks: each one's non-RL baseline over --seeds seeds, in parallel.

    With --train, also each benchmark's policy, trained once per seed and scored beside the
    baseline on the same evaluation episodes.

    Prints one table: benchmark, Flow's metric, mean ± std over seeds, Flow's reference.

    Metrics: mean speed (figure eight, merge), -delay (grid), last 500 s outflow (bottleneck).

    Reference: the score Flow's scripts expect of a trained policy.

    --set applies to every benchmark (e.g. --set env.horizon=50 for a short run). Without
    names, every benchmark runs for 50 steps as a quick look: `flowrun benchmark all` runs
    them at full length.

    Results: OUT/benchmark/<timestamp>/ (results.json, results.md, benchmark.png, run folders).

    Ctrl-C/SIGTERM keeps the finished runs and writes their table (exit 130/143).
    """
    if not names:
        console.print(f"a quick look: every benchmark for {QUICK_STEPS} steps; "
                      "`flowrun benchmark all` runs them at full length", highlight=False)
    plan = make_plan(names or [], seeds, jobs, train, configs, record, seed, set_ or [], out,
                     budget)  # fmt: skip
    _run(plan, jobs or os.cpu_count() or 1)


def _within_budget(plan: BenchmarkPlan, minutes: float) -> BenchmarkPlan:
    """Refuse a plan whose estimate exceeds the budget; else say the estimate and give the
    trainings its deadline."""
    from flowrun.preflight.budget import PROBE_TEXT, benchmark_budget

    if not plan.train:
        raise ConfigError("--budget limits the trainings of --train; add --train or drop it")
    console.print(f"estimating the wall time: {PROBE_TEXT}, per benchmark", highlight=False)
    paths = [bench.config_path(plan.configs) for bench in plan.benchmarks]
    fits = benchmark_budget(paths, plan.sets, len(plan.seeds), minutes)
    console.print(fits.describe(), highlight=False, markup=False)
    return replace(plan, deadline=fits.deadline_text)


def _run(plan: BenchmarkPlan, jobs: int) -> None:
    """Baselines (and trainings), then the policies' evaluations; then the results."""
    from flowrun.experiment import benchmark_run as br

    failures: list[str] = []
    first = [(_point(b, "baseline", s), br.baseline_command(plan, b, s))
             for b in plan.benchmarks for s in plan.baseline_seeds]  # fmt: skip
    if plan.train:
        first += [(_point(b, "train", s), br.train_command(plan, b, s))
                  for b in plan.benchmarks for s in plan.seeds]  # fmt: skip
    try:
        _pool(first, jobs, failures)
        if plan.train:
            second = []
            for bench in plan.benchmarks:
                for s in plan.seeds:
                    run_dir = br.train_run(plan, bench, s)
                    if run_dir is not None:
                        second.append((_point(bench, "policy", s),
                                       br.policy_command(plan, bench, s, run_dir)))  # fmt: skip
            _pool(second, jobs, failures)
    except KeyboardInterrupt as err:
        _report(plan, "interrupted")
        raise interrupted_exit(err, f"finished runs kept in {plan.folder}") from None
    _report(plan, "complete" if not failures else "failed")
    if failures:
        for line in failures:
            typer.secho(f"failed: {line}", err=True, fg=typer.colors.RED)
        raise FlowrunError(f"{len(failures)} run(s) failed (above); results in {plan.folder}")


def _pool(commands: list[tuple[SweepPoint, list[str]]], jobs: int, failures: list[str]) -> None:
    if not commands:
        return
    columns = (TextColumn("benchmark"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
               TextColumn("{task.fields[last]}"))  # fmt: skip
    done = [0]
    feedback = Feedback(console)
    describe = describe_points("benchmark")
    with feedback.progress(columns, describe, len(commands), last="") as update:

        def on_done(point: SweepPoint, code: int, last: str) -> None:
            values = dict(point.values)
            what = f"{values['benchmark']} {values['run']} seed {point.seed}"
            if code != 0:
                failures.append(f"{what}: exit {code}: {last}")
            done[0] += 1
            update(completed=done[0], last=what)

        run_points(commands, jobs, on_done)


def _report(plan: BenchmarkPlan, status: str) -> None:
    """Write results.json / results.md / benchmark.png and print the table."""
    from flowrun.experiment import benchmark_report as report
    from flowrun.experiment.benchmark_run import collect

    rows = collect(plan)
    try:
        json_path, md_path, plot = report.write_results(plan, rows, sys.argv, status)
    except OSError as err:
        raise FlowrunError(f"cannot write results in {plan.folder}: {err.strerror}") from None
    console.print(results_table(plan, rows))
    for line in report.notes(rows):
        console.print(line, highlight=False, markup=False)
    shown = f"; plot: {plot.name}" if plot is not None else ""
    console.print(f"results: {json_path} and {md_path.name}{shown}")


def results_table(plan: BenchmarkPlan, rows: list[dict[str, Any]]) -> Table:
    """The terminal table: one row per benchmark."""
    from flowrun.experiment.benchmark_report import table_rows

    header, cells = table_rows(rows, plan.train)
    table = Table(title=f"Flow's benchmarks: {len(plan.seeds)} seed(s), {plan.folder}")
    for col in header:
        table.add_column(col, justify="left" if col in ("benchmark", "metric") else "right",
                         overflow="fold")  # fmt: skip
    for line in cells:
        table.add_row(*line)
    return table


def register(app: typer.Typer) -> None:
    """Add ``benchmark`` to the app."""
    app.command("benchmark")(benchmark)

