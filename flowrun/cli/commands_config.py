"""``flowrun validate`` and ``flowrun list``: check a config; show the names a config may use."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import typer

from flowrun.cli.common import SeedOpt, SetOpt, guarded, overrides_with_seed
from flowrun.controllers.registry import controller_lines
from flowrun.envs.registry import env_names
from flowrun.errors import ConfigError
from flowrun.networks.registry import network_lines
from flowrun.suggest import unknown_name

# ``flowrun list WHAT`` -> the function returning its lines.
LISTS: dict[str, Callable[[], list[str]]] = {
    "envs": env_names,
    "networks": network_lines,  # with their parameters
    "controllers": controller_lines,  # with their parameters
}


def list_names(what: str) -> list[str]:
    """The names a config may use for ``what`` (``envs``, ``networks`` or ``controllers``).

    Raises:
        ConfigError: ``what`` is not one of those (with a did-you-mean).
    """
    if what not in LISTS:
        raise ConfigError(unknown_name("list", what, LISTS))
    return LISTS[what]()


def register(app: typer.Typer) -> None:
    """Add the ``validate`` and ``list`` commands to ``app``."""

    @app.command("validate")
    @guarded
    def validate(
        config: Annotated[
            Path,
            typer.Argument(
                help="Experiment config (YAML), or a Flow config module (.py defining "
                "flow_params).",
                metavar="CONFIG",
            ),
        ],
        set_: SetOpt = None,
        seed: SeedOpt = None,
    ) -> None:
        """Check CONFIG as baseline and train would, then print the resolved config as YAML.

        CONFIG is a YAML file or a Flow config module (a .py file defining flow_params; it
        is imported, so its top-level code runs).
        Every problem a run would refuse is reported here first, as one line with the file,
        line and key path, and exit code 1; nothing is written. Settings that would have no
        effect are warned about, and so is a train: section whose algorithm needs a package
        that is not installed (the config is valid and baseline runs it; train refuses it).
        An import path (env.class: my_envs:MyEnv, a controller type: pkg.mod:Class) is
        imported to check it, so its module's top-level code runs, as it would in
        baseline/train. --set and --seed as in baseline/train, e.g.
        --set sim.step=0.5 --set vehicles[0].count=10.
        """
        from flowrun.config import dump_config
        from flowrun.preflight.checks import validate_config

        cfg = validate_config(config, overrides_with_seed(set_, seed))
        typer.echo(dump_config(cfg), nl=False)

    @app.command("list")
    @guarded
    def list_(
        what: Annotated[str, typer.Argument(help="envs, networks or controllers.", metavar="WHAT")],
    ) -> None:
        """List the environment, network or controller names a config may use."""
        for name in list_names(what):
            typer.echo(name)
