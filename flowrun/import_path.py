"""A user's class named by an import path ``package.module:Class`` (``env.class``,
``network.type``), imported from the config file's folder when it is not importable already."""

from __future__ import annotations

import contextlib
import importlib
import pkgutil
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

from flowrun.errors import ConfigError
from flowrun.suggest import did_you_mean


def import_near(
    module_name: str, name: str, search_dir: Path | None, what: str, key: str
) -> ModuleType:
    """Import ``module_name``, from ``search_dir`` too when it holds the top-level package.

    ``search_dir`` is appended to ``sys.path`` (so an installed package of the same name wins).

    Args:
        module_name: the module part of the import path.
        name: the whole import path, for the message.
        search_dir: the config file's folder, or ``None``.
        what: what the class is (``environment``), for the message.
        key: the error's key path (``env.class``).

    Raises:
        ConfigError: the module (or one of its imports) cannot be imported; with a
            did-you-mean among the modules that exist where it was looked for.
    """
    top = module_name.split(".")[0]
    try:
        return importlib.import_module(module_name)
    except ModuleNotFoundError as err:
        here = search_dir is not None and (
            (search_dir / top).is_dir() or (search_dir / f"{top}.py").is_file()
        )
        if err.name != top or not here:
            raise _import_error(module_name, name, err, search_dir, what, key) from err
    if str(search_dir) not in sys.path:
        sys.path.append(str(search_dir))
    importlib.invalidate_caches()
    try:
        return importlib.import_module(module_name)
    except ImportError as err:
        raise _import_error(module_name, name, err, search_dir, what, key) from err


def class_at(module: ModuleType, qualname: str) -> Any:
    """``module.<qualname>`` (dotted for a nested class), ``None`` when absent."""
    obj: Any = module
    for part in qualname.split("."):
        obj = getattr(obj, part, None)
        if obj is None:
            return None
    return obj


def _import_error(
    module_name: str, name: str, err: ImportError, search_dir: Path | None, what: str, key: str
) -> ConfigError:
    missing = getattr(err, "name", None) or ""
    parent = missing.rpartition(".")[0]
    hint = ""
    if missing and module_name.startswith(missing):
        # The module itself (not one of its imports) is missing: suggest a sibling module.
        places: list[str] = []
        if parent:
            with contextlib.suppress(ImportError):
                places = list(getattr(importlib.import_module(parent), "__path__", []))
        elif search_dir is not None:
            places = [str(search_dir)]
        prefix = f"{parent}." if parent else ""
        names = [prefix + m.name for m in pkgutil.iter_modules(places)]
        hint = did_you_mean(missing, names) if names else ""
    where = f" (looked in {search_dir} too)" if search_dir is not None else ""
    return ConfigError(
        f"cannot import module '{module_name}' for {what} '{name}': {err}{hint}{where}; "
        "put the package next to the config file, install it, or add its folder to PYTHONPATH",
        path=key,
    )
