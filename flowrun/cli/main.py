"""``flowrun``: one Typer app; each command lives in its own module and calls the library.

The commands are loaded lazily: ``flowrun --help`` lists them from :data:`COMMANDS` and
``flowrun NAME`` imports only NAME's module (training, plotting and the simulator are heavy
imports a ``--help`` or ``list`` should not pay for).

Domain errors (:class:`flowrun.errors.FlowrunError`) become one line on stderr and exit code 1.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Iterator, MutableMapping
from typing import Any

import typer
from typer.core import TyperCommand, TyperGroup

from flowrun import __version__
from flowrun.errors import FlowrunError

#: Every command: its module (whose ``register(app)`` adds it) and its one-line help, in the
#: order ``flowrun --help`` lists them. tests/test_cli_startup.py checks the lines match the
#: commands' own.
COMMANDS: dict[str, tuple[str, str]] = {
    "baseline": ("commands_run", "Run a config's non-RL experiment: a table and MCAP logs."),
    "train": ("commands_train", "Train the config's policy, then evaluate it."),
    "eval": ("commands_train", "Roll out a trained policy beside its baseline."),
    "replay": ("commands_replay", "Summarise, compare, plot, export or repair MCAP logs."),
    "sweep": ("commands_sweep", "Run a baseline for every combination of --grid values."),
    "benchmark": ("commands_benchmark", "Run Flow's benchmarks: baselines, policies with --train."),
    "validate": ("commands_config", "Check a config, then print it resolved as YAML."),
    "list": ("commands_config", "List the env, network or controller names."),
    "convert": ("commands_convert", "Print a Flow config module as a YAML config."),
}


def load_commands(module: str) -> dict[str, Any]:
    """The click commands that ``flowrun.cli.<module>``'s ``register`` adds to an app (a
    dotted ``module`` is a full module path). Ctrl-C while it is imported (the heavy part of
    starting a command) exits 130 with one line, no traceback."""
    sub = typer.Typer(rich_markup_mode=None)
    try:
        found = importlib.import_module(module if "." in module else f"flowrun.cli.{module}")
    except KeyboardInterrupt:
        typer.echo("interrupted", err=True)
        raise typer.Exit(code=130) from None
    found.register(sub)
    return dict(typer.main.get_group(sub).commands)


class LazyCommands(MutableMapping[str, Any]):
    """The commands by name, each module imported the first time one of its commands is
    looked up; iterating lists the names without importing anything."""

    def __init__(self) -> None:
        self.loaded: dict[str, Any] = {}

    def __getitem__(self, name: str) -> Any:
        if name not in self.loaded and name in COMMANDS:
            self.loaded.update(load_commands(COMMANDS[name][0]))
        return self.loaded[name]

    def __setitem__(self, name: str, command: Any) -> None:
        self.loaded[name] = command

    def __delitem__(self, name: str) -> None:
        del self.loaded[name]

    def __iter__(self) -> Iterator[str]:
        return iter(dict.fromkeys([*COMMANDS, *self.loaded]))

    def __len__(self) -> int:
        return len(dict.fromkeys([*COMMANDS, *self.loaded]))


class LazyGroup(TyperGroup):
    """flowrun's command group: commands imported when one is run or its help is shown; the
    group's own ``--help`` lists them from :data:`COMMANDS` without importing them."""

    _listing = False

    def __init__(self, **attrs: Any) -> None:
        super().__init__(**attrs)
        lazy = LazyCommands()
        lazy.loaded.update(self.commands)
        self.commands = lazy

    def list_commands(self, ctx: Any) -> list[str]:
        return list(self.commands)

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        loaded = self.commands.loaded  # type: ignore[attr-defined]
        if self._listing and cmd_name not in loaded and cmd_name in COMMANDS:
            return TyperCommand(cmd_name, short_help=COMMANDS[cmd_name][1])
        return self.commands.get(cmd_name)

    def format_help(self, ctx: Any, formatter: Any) -> None:
        self._listing = True
        try:
            super().format_help(ctx, formatter)
        finally:
            self._listing = False


app = typer.Typer(
    name="flowrun",
    cls=LazyGroup,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)


def show_version(value: bool) -> None:
    """``--version``: print flowrun's version and exit."""
    if value:
        typer.echo(f"flowrun {__version__}")
        raise typer.Exit()


@app.callback()
def flowrun(
    version: bool = typer.Option(
        False,
        "--version",
        help="Print flowrun's version and exit.",
        callback=show_version,
        is_eager=True,
        show_default=False,
    ),
) -> None:
    """Mixed-autonomy traffic experiments on SUMO: baseline runs, RL training, log replay.

    `flowrun COMMAND --help` shows a command's arguments and options.
    """


def main() -> None:
    """Console-script entry point."""
    try:
        app(prog_name="flowrun")
    except FlowrunError as err:  # commands use cli.common.guarded; this is the last resort
        typer.echo(f"error: {err}", err=True)
        sys.exit(1)
    except KeyboardInterrupt:  # Ctrl-C before a command installed its own handling
        typer.echo("interrupted", err=True)
        sys.exit(130)


if __name__ == "__main__":  # ``python -m flowrun.cli.main``: how ``flowrun sweep`` starts points
    main()
