"""``flowrun convert``: a Flow config module (``flow_params``) as the equivalent YAML config."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Annotated

import typer

from flowrun.cli.common import SeedOpt, SetOpt, guarded, out_option, overrides_with_seed
from flowrun.errors import ConfigError

#: ``--out`` ending so names the YAML file itself (the spelling before ``--out`` meant a folder).
YAML_SUFFIXES = (".yaml", ".yml")


def convert_text(config: Path, overrides: Sequence[str] = ()) -> str:
    """The YAML config equivalent to the Flow config module ``config``.

    Loading the YAML (from the module's folder when its env class is defined in the module)
    gives a config equal to the module's, with ``overrides`` (``key.path=value``) applied.

    Raises:
        ConfigError: ``config`` is not a ``.py`` file, or the module, its ``flow_params``
            or an override is invalid.
    """
    from flowrun.config.dump import dump_config
    from flowrun.loading.flow_module import is_flow_module, load_flow_module
    from flowrun.loading.loader import override_config

    if not is_flow_module(config):
        raise ConfigError(
            "expected a Flow config module (a .py file defining flow_params); "
            "a YAML config needs no conversion (see flowrun validate)",
            "",
            str(config),
        )
    cfg = load_flow_module(config).config
    header = f"# converted by flowrun convert from {config.name}\n"
    if overrides:
        cfg = override_config(cfg, list(overrides))
        header += f"# with --set {' --set '.join(overrides)}\n"
    return header + dump_config(cfg)


def converted_path(config: Path, out: Path) -> Path:
    """Where ``--out`` puts the YAML: ``OUT/<module name>.yaml``; an ``OUT`` ending in
    ``.yaml``/``.yml`` that is not a folder is the file itself (the older spelling)."""
    if out.suffix.lower() in YAML_SUFFIXES and not out.is_dir():
        return out
    return out / f"{config.stem}.yaml"


def register(app: typer.Typer) -> None:
    """Add the ``convert`` command to ``app``."""

    @app.command("convert")
    @guarded
    def convert(
        config: Annotated[
            Path,
            typer.Argument(
                help="Flow config module (.py defining flow_params).",
                metavar="MODULE",
                show_default=False,
            ),
        ],
        set_: SetOpt = None,
        seed: SeedOpt = None,
        out: Annotated[
            Path | None,
            out_option(
                "the YAML as a new file OUT/<module name>.yaml (an OUT ending in .yaml is "
                "that file; default: print the YAML)"
            ),
        ] = None,
    ) -> None:
        """Print the YAML config equivalent to a Flow config module (flow_params).

        MODULE is imported, so its top-level code runs (as Flow's own scripts would run
        it). --set and --seed change the written config (as they would change a run of it).
        """
        text = convert_text(config, overrides_with_seed(set_, seed))
        if out is None:
            typer.echo(text, nl=False)
            return
        if out.exists() and not out.is_dir() and out.suffix.lower() not in YAML_SUFFIXES:
            raise ConfigError("is a file; --out names a folder (or a new .yaml file)", "", str(out))
        path = converted_path(config, out)
        if path.exists() or path.is_symlink():
            raise ConfigError("exists already; choose another file name", "", str(path))
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with path.open("x", encoding="utf-8") as f:
                f.write(text)
        except FileExistsError:
            raise ConfigError("exists already; choose another file name", "", str(path)) from None
        except OSError as err:
            raise ConfigError(f"cannot write: {err.strerror}", "", str(path)) from None
        typer.echo(f"wrote {path}", err=True)
