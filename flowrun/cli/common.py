"""What the CLI commands share: error reporting, the common options, interruptions.

The options every command that runs something takes, defined once so they mean the same
everywhere::

    def cmd(config: ConfigArg, set_: SetOpt = None, seed: SeedOpt = None,
            out: OutOpt = DEFAULT_OUT) -> None:
        cfg = load_config(config, overrides_with_seed(set_, seed))

- ``--set a.b=value``: override a config value (YAML scalar, never ``eval``); repeatable;
- ``--seed N``: the experiment's seed (``sim.seed``), applied after every ``--set``;
- ``--out DIR``: always a *folder that receives* what the command makes, each time in a new
  folder or file of its own (nothing is overwritten): run folders (baseline, train, sweep),
  evaluation folders (eval), replay folders of plots (replay), the converted YAML (convert).
  :func:`out_option` words its help the same way on every command.

A command that runs nothing says in its help why it takes no ``--seed``/``--set``
(:data:`NO_SEED_OR_SET`).

Interruptions: inside :func:`interrupt_between_steps` (or :func:`sigterm_as_interrupt`),
Ctrl-C and SIGTERM raise :class:`~flowrun.rundir.folders.Interrupted`, a
``KeyboardInterrupt`` that carries the signal; :func:`interrupted_exit` turns it into
exit code 130 (SIGINT) or 143 (SIGTERM).
"""

from __future__ import annotations

import errno
import functools
import io
import signal
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, ParamSpec, TypeVar

import typer

from flowrun.errors import FlowrunError

if TYPE_CHECKING:
    from flowrun.config.model import ExperimentConfig
    from flowrun.config.yamlio import Locations

P = ParamSpec("P")
R = TypeVar("R")

#: Where run folders go unless ``--out`` says otherwise.
DEFAULT_OUT = Path("runs")

SetOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--set",
        metavar="KEY=VALUE",
        help="Override a config value: a.b=value (read as a YAML scalar). Repeatable.",
    ),
]
SeedOpt = Annotated[
    int | None,
    typer.Option("--seed", metavar="N", help="Seed (overrides sim.seed and any --set of it)."),
]
# Options of ``flowrun baseline`` that ``flowrun sweep`` also takes and passes on to it.
StepsOpt = Annotated[
    int | None,
    typer.Option("--steps", metavar="N", help="Steps per run (default: env.horizon)."),
]
NoRecordOpt = Annotated[bool, typer.Option("--no-record", help="Do not write MCAP logs.")]
#: How the help of every ``--out`` starts: the option always names a folder.
OUT_HELP = "Folder that receives"


def out_option(receives: str) -> Any:
    """The ``--out`` option, its help saying what the folder receives (``receives``)."""
    return typer.Option(
        "--out",
        metavar="DIR",
        help=f"{OUT_HELP} {receives}; nothing in it is overwritten.",
        callback=expand_home,
    )


def expand_home(path: Path | None) -> Path | None:
    """``~`` at the start of a path is the home folder, also when the shell left it alone
    (quoted, or in ``--out=~/runs``): SUMO's tools expand it themselves, so a literal ``~``
    folder would break their paths."""
    return path.expanduser() if path is not None else None


OutOpt = Annotated[Path, out_option("the run folders, OUT/<config name>/...")]
ConfigArg = Annotated[
    Path, typer.Argument(help="Experiment YAML file.", metavar="CONFIG", show_default=False)
]
AnyConfigArg = Annotated[
    Path,
    typer.Argument(
        help="Experiment YAML file, or a Flow config module (.py defining flow_params).",
        metavar="CONFIG",
        show_default=False,
    ),
]

#: The long names of the options above: ``--help`` of every command that runs something
#: lists them (tests/test_runs_options.py checks).
COMMON_OPTIONS = ("--out", "--seed", "--set")
#: What the help of a command that runs no simulation says instead of offering them.
NO_SEED_OR_SET = "runs no simulation, so it takes no --seed or --set"


def printable_output() -> None:
    """Print what the terminal's encoding cannot show as ``?`` instead of failing: a Latin-1
    terminal (``PYTHONIOENCODING=latin-1``) made the table's "..." raise a traceback after a
    finished run."""
    for stream in (sys.stdout, sys.stderr):
        if isinstance(stream, io.TextIOWrapper):
            with suppress(ValueError, io.UnsupportedOperation):
                stream.reconfigure(errors="replace")


def guarded(fn: Callable[P, R]) -> Callable[P, R]:
    """Turn a :class:`FlowrunError` raised by a command into one stderr line and exit code 1
    (and make the output streams replace what their encoding cannot show)."""

    @functools.wraps(fn)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        printable_output()
        try:
            return fn(*args, **kwargs)
        except FlowrunError as err:
            typer.secho(f"error: {one_line(str(err))}", err=True, fg=typer.colors.RED)
            raise typer.Exit(code=1) from None
        except OSError as err:
            if err.filename is None:  # not about a path the user gave: a real failure
                raise
            typer.secho(f"error: {path_problem(err)}", err=True, fg=typer.colors.RED)
            raise typer.Exit(code=1) from None

    return wrapper


def path_problem(err: OSError) -> str:
    """One line for a file-system error on a path: which path, what, how to fix a name too
    long (a folder or file name over 255 bytes, the limit of Linux file systems)."""
    path = str(err.filename)
    if err.errno == errno.ENAMETOOLONG:
        longest = max(len(part.encode()) for part in Path(path).parts)
        return (
            f"{path}: file name too long (a part of it is {longest} bytes; file systems "
            "allow 255): use a shorter name"
        )
    return f"{path}: {err.strerror}"


def load_located(config: Path, overrides: list[str]) -> tuple[ExperimentConfig, Locations]:
    """A YAML config or Flow config module with its ``--set`` overrides, and where its keys
    stand, so that the checks a run makes before it starts
    (:func:`flowrun.preflight.checks.preflight`) name ``file:line`` as ``validate`` does."""
    from flowrun.config.yamlio import Locations
    from flowrun.loading.flow_module import is_flow_module, load_any_config
    from flowrun.loading.loader import load_config_located

    if is_flow_module(config):
        return load_any_config(config, overrides), Locations(str(config))
    return load_config_located(config, overrides)


def one_line(message: str) -> str:
    """``message`` on one line: a tool's multi-line output quoted in an error (netconvert's
    ``Error: ...`` lines) joined with spaces."""
    return " ".join(part.strip() for part in message.splitlines() if part.strip())


def overrides_with_seed(sets: list[str] | None, seed: int | None) -> list[str]:
    """``--set`` values plus ``--seed`` as the override ``sim.seed=S`` (last, so it wins).

    Raises:
        ConfigError: ``seed`` is negative or too large for the simulator and SB3.
    """
    from flowrun.config.checks import MAX_SEED
    from flowrun.errors import ConfigError

    items = list(sets or [])
    if seed is not None and not 0 <= seed <= MAX_SEED:
        raise ConfigError(f"--seed must be between 0 and {MAX_SEED}, got {seed}")
    if seed is not None:
        items.append(f"sim.seed={seed}")
    return items


@contextmanager
def on_stop_signals(handler: Callable[[int, Any], None]) -> Iterator[None]:
    """Ctrl-C (SIGINT) and SIGTERM call ``handler`` while inside; the previous handlers are
    restored on the way out."""
    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Raise SIGTERM as :class:`Interrupted` (like Ctrl-C) so ``finally`` blocks run.

    Ctrl-C raises :class:`Interrupted` too, so the exit code can tell the two apart.
    """

    from flowrun.rundir.folders import Interrupted

    received: list[int] = []

    def handler(signum: int, frame: Any) -> None:
        received.append(signum)
        raise Interrupted(signum)

    previous_hook = sys.unraisablehook

    def unraisable(args: Any) -> None:
        # the signal landed in a callback whose exceptions Python ignores (a garbage
        # collector's weakref callback, a __del__): raised again below, without the noise
        if not isinstance(args.exc_value, Interrupted):
            previous_hook(args)

    sys.unraisablehook = unraisable
    try:
        with on_stop_signals(handler):
            yield
            if received:  # the work went on after an ignored interruption: stop now
                raise Interrupted(received[0])
    finally:
        sys.unraisablehook = previous_hook


@contextmanager
def interrupt_between_steps() -> Iterator[Callable[[], None]]:
    """Ctrl-C/SIGTERM stop the run at the next step boundary (a second signal stops at once).

    Yields a ``check()`` to call between steps: it raises :class:`Interrupted` once a signal
    came. Raising from inside the signal handler could land in the middle of writing the log
    (the mcap writer compressing a chunk) and silently drop that chunk's steps.
    """
    from flowrun.rundir.folders import Interrupted

    received: list[int] = []

    def handler(signum: int, frame: Any) -> None:
        if received:
            raise Interrupted(received[0])
        received.append(signum)

    def check() -> None:
        if received:
            raise Interrupted(received[0])

    with on_stop_signals(handler):
        yield check


def interruption_of(check_stop: Callable[[], None]) -> KeyboardInterrupt | None:
    """The interruption ``check_stop`` (from :func:`interrupt_between_steps`) raises, or
    ``None`` when no signal came."""
    try:
        check_stop()
    except KeyboardInterrupt as err:
        return err
    return None


def interrupted_exit(err: KeyboardInterrupt, message: str) -> typer.Exit:
    """Print ``interrupted: message`` and return the exit to raise (130 SIGINT, 143 SIGTERM)."""
    from flowrun.rundir.folders import exit_code_of

    typer.secho(f"interrupted: {message}", err=True, fg=typer.colors.YELLOW)
    return typer.Exit(code=exit_code_of(err))
