"""Is the library a ``train:`` section names installed? Asked before any process starts.

``train.algorithm`` needs torch and stable-baselines3, and ARS and TRPO also sb3-contrib;
``train.backend: rllib`` needs Ray RLlib and torch. A missing one is a :class:`ConfigError` at
the ``file:line`` of ``train.algorithm`` (or ``train.backend``) naming the package, the command
that installs it and, when stable-baselines3 is there, the algorithms that are installed.

``train`` and ``benchmark --train`` refuse such a config; ``validate`` only warns (the config
itself is valid and ``baseline`` runs it), through :func:`training_library_problem`.
"""

from __future__ import annotations

from flowrun.config.model import ExperimentConfig
from flowrun.config.yamlio import Locations
from flowrun.errors import ConfigError

#: The distribution (what pip installs) of each module the extras provide.
PACKAGES = {
    "torch": "torch",
    "stable_baselines3": "stable-baselines3",
    "sb3_contrib": "sb3-contrib",
    "ray": "ray[rllib]",
}


def required_modules(cfg: ExperimentConfig) -> tuple[str, ...]:
    """The modules training ``cfg`` imports (none without a ``train:`` section)."""
    train = cfg.train
    if train is None:
        return ()
    if train.backend == "rllib":
        return ("torch", "ray.rllib")
    from flowrun.training.algorithms import ALGORITHMS

    module = ALGORITHMS.get(train.algorithm, ("stable_baselines3", ""))[0]
    return ("torch", "stable_baselines3", module)


def missing_module(modules: tuple[str, ...]) -> str | None:
    """The first of ``modules`` (or a module it imports) that cannot be imported, else None."""
    from flowrun.training.deps import import_module

    for name in modules:
        try:
            import_module(name)
        except ModuleNotFoundError as err:
            return err.name or name
    return None


def training_library_problem(cfg: ExperimentConfig, loc: Locations) -> ConfigError | None:
    """The error for a ``train:`` section whose library is not installed, else None."""
    train = cfg.train
    if train is None:
        return None  # nothing of flowrun.training imported (validate stays light)
    missing = missing_module(required_modules(cfg))
    if missing is None:
        return None
    from flowrun.training.deps import INSTALL_HINT as TRAIN_INSTALL
    from flowrun.training.rllib.deps import INSTALL_HINT as RLLIB_INSTALL

    package = PACKAGES.get(missing.split(".")[0], missing)
    if train.backend == "rllib":
        return loc.error(
            f"RLlib needs {package} (module '{missing}'), which is not "
            f"installed; install the rllib extra: {RLLIB_INSTALL}",
            ("train", "backend"),
        )
    return loc.error(
        f"{train.algorithm} needs {package} (module '{missing}'), which is not installed; "
        f"install the train extra: {TRAIN_INSTALL}{_installed_note(train.algorithm)}",
        ("train", "algorithm"),
    )


def check_training_installed(cfg: ExperimentConfig, loc: Locations) -> None:
    """Refuse a ``train:`` section whose library is not installed (see the module doc).

    Raises:
        ConfigError: at ``train.algorithm`` or ``train.backend``.
    """
    problem = training_library_problem(cfg, loc)
    if problem is not None:
        raise problem


def _installed_note(algorithm: str) -> str:
    """``; installed: PPO, A2C, ...`` when other algorithms can train here."""
    from flowrun.training.algorithms import ALGORITHMS

    ready = [
        name for name, (module, _) in ALGORITHMS.items()
        if name != algorithm and missing_module(("torch", "stable_baselines3", module)) is None
    ]
    return f"; or use one that is installed: {', '.join(ready)}" if ready else ""
