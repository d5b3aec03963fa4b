"""Reading a Ray Tune trial folder's saved configuration (Flow's ``get_rllib_config`` and
``get_rllib_pkl``): ``params.json`` / ``params.pkl`` in a checkpoint folder or its parent."""

from __future__ import annotations

import json
import os
import pickle
from pathlib import Path
from typing import Any

from flowrun.errors import TrainingError


class MissingTrialFileError(TrainingError, ValueError):
    """No ``params.json``/``params.pkl`` where Ray writes it. Also a ``ValueError``, which is
    what Flow raised."""


def _trial_file(path: str | os.PathLike[str], name: str) -> Path:
    folder = Path(path)
    for candidate in (folder / name, folder.parent / name):
        if candidate.is_file():
            return candidate
    raise MissingTrialFileError(
        f"no {name} in {folder} or its parent folder; give a Ray Tune trial folder or one of "
        "its checkpoint folders"
    )


def get_rllib_config(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The trial's configuration as saved in ``params.json`` (in ``path`` or its parent).

    Raises:
        MissingTrialFileError: neither folder holds ``params.json``.
    """
    data: dict[str, Any] = json.loads(_trial_file(path, "params.json").read_text())
    return data


def get_rllib_pkl(path: str | os.PathLike[str]) -> Any:
    """The trial's configuration as pickled in ``params.pkl`` (in ``path`` or its parent).

    Unpickling runs code the file names: load only files you trust (your own runs).

    Raises:
        MissingTrialFileError: neither folder holds ``params.pkl``.
    """
    with _trial_file(path, "params.pkl").open("rb") as f:
        return pickle.load(f)  # the user's own trial file, as Flow's
