"""Read a Flow experiment config module (a ``.py`` file that defines ``flow_params``).

The module runs as Flow's ``exp_configs`` do: imported once, top to bottom. It is imported
under its file's stem when that name is free (so ``env.class: exp_config:MyEnv`` in the
converted YAML imports the same file again), else under a private name; either way it is
put in ``sys.modules`` so a user env class defined in it resolves to that very class.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import os
import sys
import traceback
import warnings
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType

from flowrun.config.model import ExperimentConfig
from flowrun.errors import ConfigError
from flowrun.loading.flow_params import FlowExperiment, from_flow_params
from flowrun.loading.loader import load_config, override_config


def is_flow_module(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` names a Python config module (``.py``) rather than a YAML file."""
    return Path(path).suffix == ".py"


def _module_name(file: Path) -> str:
    """The stem if importing it would give this file (or nothing else), else a private name."""
    stem = file.stem
    private = f"_flowrun_config_{abs(hash(str(file))):x}"
    if not stem.isidentifier():
        return private
    try:
        spec = importlib.util.find_spec(stem)
    except (ImportError, ValueError):
        return private
    if spec is None:
        return stem
    origin = spec.origin
    return stem if origin and Path(origin).resolve() == file else private


def _import(file: Path, source: str) -> ModuleType:
    name = _module_name(file)
    spec = importlib.util.spec_from_file_location(name, file)
    if spec is None or spec.loader is None:
        raise ConfigError("cannot be imported as a Python module", "", source)
    module = importlib.util.module_from_spec(spec)
    folder = str(file.parent)
    if folder not in sys.path:
        sys.path.append(folder)  # its own helper modules, as when Flow imports it
    previous = sys.modules.get(name)
    sys.modules[name] = module
    try:
        with warnings.catch_warnings():
            # Flow's deprecated spellings (InFlows.add(vehsPerHour=...)) are shown, not hidden
            warnings.simplefilter("default", DeprecationWarning)
            spec.loader.exec_module(module)
    except (KeyboardInterrupt, SystemExit) as err:
        _restore(name, previous)
        if isinstance(err, KeyboardInterrupt):
            raise
        raise ConfigError("exits while being imported (sys.exit)", "", source) from None
    except BaseException as err:
        _restore(name, previous)
        raise ConfigError(
            f"importing the config failed: {type(err).__name__}: {err}", "", _where(err, file)
        ) from None
    return module


def _restore(name: str, previous: ModuleType | None) -> None:
    if previous is None:
        sys.modules.pop(name, None)
    else:
        sys.modules[name] = previous


def _where(err: BaseException, file: Path) -> str:
    """``file:line`` of the deepest frame of ``err`` inside ``file`` (else ``file``)."""
    if isinstance(err, SyntaxError) and err.lineno:
        return f"{file}:{err.lineno}"
    line = None
    for frame in traceback.extract_tb(err.__traceback__):
        if Path(frame.filename).resolve() == file:
            line = frame.lineno
    return f"{file}:{line}" if line else str(file)


def load_flow_module(path: str | os.PathLike[str]) -> FlowExperiment:
    """Import a Flow config module and read its ``flow_params``.

    Raises:
        ConfigError: the file is missing, raises on import (with the line), defines no
            ``flow_params``, or its ``flow_params`` is invalid.
    """
    source = str(path)
    file = Path(path).resolve()
    if not file.is_file():
        raise ConfigError(f"config file not found (looked for {file}); check the path", "", source)
    module = _import(file, source)
    params = getattr(module, "flow_params", None)
    if params is None:
        raise ConfigError(
            "defines no 'flow_params'; a Flow config module sets "
            "flow_params = dict(exp_tag=..., env_name=..., network=..., sim=..., env=..., "
            "net=..., veh=..., initial=...)",
            "",
            source,
        )
    return from_flow_params(params, source)


def load_any_config(
    path: str | os.PathLike[str], overrides: Sequence[str] = ()
) -> ExperimentConfig:
    """A YAML config or a Flow config module (``.py``), with ``--set`` overrides applied."""
    if not is_flow_module(path):
        return load_config(path, overrides)
    cfg = load_flow_module(path).config
    if overrides:
        cfg = override_config(cfg, list(overrides))
    return dataclasses.replace(cfg, source=str(path))
