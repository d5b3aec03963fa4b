"""``flowrun``: one Typer app; each command lives in its own module and calls the library.

Domain errors (:class:`flowrun.errors.FlowrunError`) become one line on stderr and exit code 1.
"""

from __future__ import annotations

import sys

import typer

from flowrun.errors import FlowrunError

app = typer.Typer(
    name="flowrun",
    help="Mixed-autonomy traffic experiments on SUMO: baseline runs, RL training, log replay.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _register_commands() -> None:
    # Each module adds its commands to ``app``; imported here so ``app`` exists first.
    from flowrun.cli import commands_config, commands_run, commands_sweep

    commands_run.register(app)
    commands_sweep.register(app)
    commands_config.register(app)
    from flowrun.cli import commands_replay, commands_train

    commands_replay.register(app)
    commands_train.register(app)
    from flowrun.cli import commands_benchmark

    commands_benchmark.register(app)


_register_commands()


def main() -> None:
    """Console-script entry point."""
    try:
        app()
    except FlowrunError as err:  # commands use cli.common.guarded; this is the last resort
        typer.echo(f"error: {err}", err=True)
        sys.exit(1)


if __name__ == "__main__":  # ``python -m flowrun.cli.main``: how ``flowrun sweep`` starts points
    main()
