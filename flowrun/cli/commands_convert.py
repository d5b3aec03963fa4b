"""``flowrun convert``: a Flow config module (``flow_params``) as the equivalent YAML config."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flowrun.cli.common import guarded
from flowrun.errors import ConfigError


def convert_text(config: Path) -> str:
    """The YAML config equivalent to the Flow config module ``config``.

    Loading the YAML (from the module's folder when its env class is defined in the module)
    gives a config equal to the module's.

    Raises:
        ConfigError: ``config`` is not a ``.py`` file, or the module or its ``flow_params``
            is invalid.
    """
    from flowrun.config.dump import dump_config
    from flowrun.config.flow_module import is_flow_module, load_flow_module

    if not is_flow_module(config):
        raise ConfigError(
            "expected a Flow config module (a .py file defining flow_params); "
            "a YAML config needs no conversion (see flowrun validate)",
            "",
            str(config),
        )
    flow = load_flow_module(config)
    header = f"# converted by flowrun convert from {config.name}\n"
    return header + dump_config(flow.config)


def register(app: typer.Typer) -> None:
    """Add the ``convert`` command to ``app``."""

    @app.command("convert")
    @guarded
    def convert(
        config: Annotated[
            Path,
            typer.Argument(
                help="Flow config module (.py defining flow_params).", show_default=False
            ),
        ],
        out: Annotated[
            Path | None, typer.Option("--out", help="Write the YAML to this file (new file).")
        ] = None,
    ) -> None:
        """Print the YAML config equivalent to a Flow config module (flow_params)."""
        text = convert_text(config)
        if out is None:
            typer.echo(text, nl=False)
            return
        if out.exists():
            raise ConfigError("exists already; choose another file name", "", str(out))
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_text(text, encoding="utf-8")
        except OSError as err:
            raise ConfigError(f"cannot write: {err.strerror}", "", str(out)) from None
        typer.echo(f"wrote {out}", err=True)
