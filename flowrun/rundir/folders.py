"""Run folders: ``runs/<config-name>/<timestamp>-<seed>/``, never overwritten, always labelled.

Each folder holds the resolved config, the command line, the versions, ``metrics.json``, the
logs, and ``status.json``: what became of the run. The life of a run folder::

    run_dir = start_run(out, cfg, seed, argv)   # folder + status "running" (pid, host)
    with tracked_run(run_dir):                  # at the end: "complete", "interrupted"
        ...                                     # (exit 130/143) or "failed" (+ the error)

A run killed outright (SIGKILL, power cut) keeps ``status: running``; :func:`read_status` sees
that its process is gone and answers ``cut``, so no later command takes it for finished. Use
:func:`is_complete` before trusting a folder's results.

``status.json`` holds the wall-clock facts (pid, host, times); ``metrics.json`` holds only what
the run measured, so two runs with the same seed write the same ``metrics.json``.
"""

from __future__ import annotations

import logging
import os
import platform
import shlex
import shutil
import sys
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from datetime import UTC, datetime
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from flowrun.config.dump import dump_config
from flowrun.config.model import ExperimentConfig
from flowrun.errors import ConfigError, FlowrunError
from flowrun.rundir.safeio import (
    WRITE_ERRORS,
    describe_os_error,
    write_json,
)
from flowrun.rundir.status import (
    COMPLETE,
    CUT,
    FAILED,
    INTERRUPTED,
    RUNNING,
    STATUS_FILE,
    Interrupted,
    RunStatus,
    exit_code_of,
    is_complete,
    mark_done,
    mark_running,
    read_status,
)

__all__ = [
    "COMPLETE",
    "CUT",
    "FAILED",
    "INTERRUPTED",
    "RUNNING",
    "Interrupted",
    "RunStatus",
    "check_out_dir",
    "check_sumo_path",
    "create_run_dir",
    "describe_os_error",
    "exit_code_of",
    "is_complete",
    "log_metadata",
    "mark_done",
    "mark_running",
    "read_status",
    "start_run",
    "tracked_run",
    "unique_dir",
    "versions",
    "write_json",
]

log = logging.getLogger(__name__)

PACKAGES = (
    "flowrun",
    "eclipse-sumo",
    "libsumo",
    "gymnasium",
    "numpy",
    "mcap",
    "stable-baselines3",
    "torch",
)

#: Files every run folder has from the start: a failed run with nothing else is removed.
BOOKKEEPING = frozenset(
    {"config.yaml", "command.txt", "versions.json", STATUS_FILE, "metrics.json"}
)
#: Scratch folders (SUMO's generated network files) that are not results either.
SCRATCH = frozenset({"sumo"})


def versions() -> dict[str, str]:
    """Versions of Python and the packages a run depends on."""
    found = {"python": platform.python_version(), "platform": platform.platform()}
    for name in PACKAGES:
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            continue
    return found


def log_metadata(
    cfg: ExperimentConfig, seed: int, run: int, record_every: int = 1
) -> dict[str, str]:
    """The MCAP ``flowrun`` metadata record (what ``flowrun replay`` shows and uses)."""
    found = versions()
    meta = {f"{name.replace('-', '_')}_version": v for name, v in found.items()}
    meta["sumo_version"] = found.get("eclipse-sumo", "unknown")
    meta.update(
        {
            "config_name": cfg.name,
            "seed": str(seed),
            "run": str(run),
            "sim_step": repr(cfg.sim.sim_step),
            "sims_per_step": str(cfg.env.sims_per_step),
            "record_every": str(record_every),
            "config": dump_config(cfg),
        }
    )
    return meta


def unique_dir(base: Path) -> Path:
    """Create ``base`` (or ``base-1``, ``base-2``, ... if taken) and return it: never reuse one.

    Safe against other processes creating the same name at the same moment (``mkdir`` is
    atomic).

    Raises:
        FlowrunError: the folder cannot be created (a file in the way, read-only, disk full).
    """
    path, n = base, 1
    while True:
        try:
            path.mkdir(parents=True, exist_ok=False)
            return path
        except FileExistsError:
            if not path.is_dir():
                raise FlowrunError(f"cannot create folder {path}: a file is in the way") from None
            path = base.with_name(f"{base.name}-{n}")
            n += 1
        except OSError as err:
            raise FlowrunError(f"cannot create folder {path}: {describe_os_error(err)}") from None


def check_out_dir(out: Path) -> None:
    """Refuse an ``--out`` that is a file or a read-only folder, before anything starts.

    Raises:
        FlowrunError: naming ``out`` and what is wrong with it (also a ``,`` in it:
            :func:`check_sumo_path`).
    """
    check_sumo_path(out, "--out")
    probe = out
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        raise FlowrunError(f"--out {out}: {probe} is a file, not a folder; pass a folder")
    if probe.is_dir() and not os.access(probe, os.W_OK | os.X_OK):
        raise FlowrunError(f"--out {out}: cannot write in {probe} (read-only or not yours)")


def check_sumo_path(path: Path, what: str) -> None:
    """Refuse a folder SUMO cannot take files from: its file options (``--route-files``,
    netconvert's inputs) split at ``,``, so ``runs,old/`` would be read as two paths, and
    netconvert reads ``a:b`` in an output path as a host and port.

    Raises:
        FlowrunError: ``path`` holds a ``,`` or a ``:``.
    """
    if "," in str(path):
        raise FlowrunError(
            f"{what} {path}: SUMO reads ',' in a file path as a list separator; "
            "choose a folder without ','"
        )
    if ":" in str(path):
        raise FlowrunError(
            f"{what} {path}: SUMO's netconvert reads 'a:b' in a file path as host:port; "
            "choose a folder without ':'"
        )


def run_dir_name(seed: int) -> str:
    """``<timestamp>-<seed>`` (UTC, to the second)."""
    return f"{datetime.now(UTC).strftime('%Y%m%d-%H%M%S')}-{seed}"


def _safe_name(name: str) -> str:
    bad = not name or name in {".", ".."} or any(c in name for c in "/\\\0")
    if bad or Path(name).is_absolute():
        raise ConfigError(
            f"names the run folder, so it must be a plain folder name (no '/', '\\', '..'), "
            f"got {name!r}",
            path="name",
        )
    return name


def create_run_dir(
    out: Path,
    cfg: ExperimentConfig,
    seed: int,
    argv: list[str] | None = None,
    folder: Path | None = None,
) -> Path:
    """Make a fresh run folder and write the resolved config, command line and versions.

    Args:
        out: the ``--out`` folder; the run folder is ``out/<cfg.name>/<timestamp>-<seed>``.
        cfg: the resolved config.
        seed: the run's seed.
        argv: the command line (default ``sys.argv``).
        folder: use this folder instead (``folder-1``, ... if taken), e.g. a sweep's point.

    Raises:
        ConfigError: ``cfg.name`` is not a plain folder name.
        FlowrunError: the folder cannot be created or written, or its path holds a ``,``
            (:func:`check_sumo_path`).
    """
    base = folder if folder is not None else out / _safe_name(cfg.name) / run_dir_name(seed)
    check_sumo_path(base, "run folder")
    run_dir = unique_dir(base)
    with _removed_if_unwritable(run_dir):
        (run_dir / "config.yaml").write_text(dump_config(cfg))
        command = argv if argv is not None else sys.argv
        (run_dir / "command.txt").write_text(shlex.join(command) + "\n")
        write_json(run_dir / "versions.json", versions())
    return run_dir


def start_run(
    out: Path,
    cfg: ExperimentConfig,
    seed: int,
    argv: list[str] | None = None,
    folder: Path | None = None,
) -> Path:
    """:func:`create_run_dir`, then mark it ``running`` (with this process's pid and host)."""
    run_dir = create_run_dir(out, cfg, seed, argv, folder)
    with _removed_if_unwritable(run_dir):
        mark_running(run_dir)
    return run_dir


@contextmanager
def _removed_if_unwritable(run_dir: Path) -> Iterator[None]:
    """A new run folder's first writes: if one fails (``OSError``), the folder is removed and
    the error is one :class:`FlowrunError` line."""
    try:
        yield
    except OSError as err:
        shutil.rmtree(run_dir, ignore_errors=True)
        raise FlowrunError(f"cannot write run folder {run_dir}: {describe_os_error(err)}") from None


def _has_results(run_dir: Path) -> bool:
    try:
        return any(p.name not in BOOKKEEPING | SCRATCH for p in run_dir.iterdir())
    except OSError:
        return True  # cannot tell: keep it


@contextmanager
def tracked_run(run_dir: Path, *, remove_if_empty: bool = True) -> Iterator[Path]:
    """Label ``run_dir`` with how the code in the ``with`` block ended.

    - normal end: ``complete``;
    - ``KeyboardInterrupt`` (Ctrl-C; SIGTERM raised as :class:`Interrupted`): ``interrupted``
      with exit code 130/143, then re-raised;
    - a :class:`FlowrunError`: ``failed`` with its message, re-raised; if nothing but the
      bookkeeping files was written (e.g. SUMO refused the network), the folder is removed;
    - an ``OSError`` (disk full, file size limit, read-only): ``failed`` (if that can still be
      written), raised as one :class:`FlowrunError` line without the chain of errors behind it;
    - anything else (a bug): ``failed`` with the error, re-raised as it is.

    Args:
        run_dir: the folder (from :func:`start_run`).
        remove_if_empty: remove a failed run's folder when it holds no results.

    Yields:
        ``run_dir``.
    """
    try:
        yield run_dir
    except KeyboardInterrupt as err:
        with suppress(OSError):
            mark_done(run_dir, INTERRUPTED, exit_code=exit_code_of(err))
        raise
    except OSError as err:
        if err.errno in WRITE_ERRORS:
            message = f"cannot write run folder {run_dir}: {describe_os_error(err)}"
        else:
            message = f"run failed: {describe_os_error(err)}"
        _fail(run_dir, message, remove_if_empty)
        raise FlowrunError(message) from None
    except FlowrunError as err:
        _fail(run_dir, str(err), remove_if_empty)
        raise
    except Exception as err:
        _fail(run_dir, f"{type(err).__name__}: {err}", remove_if_empty=False)
        raise
    mark_done(run_dir, COMPLETE, exit_code=0)


def _fail(run_dir: Path, message: str, remove_if_empty: bool) -> None:
    if remove_if_empty and not _has_results(run_dir):
        shutil.rmtree(run_dir, ignore_errors=True)
        with suppress(OSError):  # and runs/<name>/ if this run was all it held
            run_dir.parent.rmdir()
        return
    try:
        mark_done(run_dir, FAILED, error=message.splitlines()[0] if message else "", exit_code=1)
    except OSError as err:
        log.info("could not mark %s failed: %s", run_dir, describe_os_error(err))
