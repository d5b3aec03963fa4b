"""A train run folder's state: a lock held while training, its status, and stop requests.

``status.json`` (:mod:`flowrun.rundir.status`, shared by every command) and
``metrics.json`` say ``running`` from the start of training, then ``complete``,
``interrupted`` (Ctrl-C/SIGTERM: a checkpoint was saved) or ``failed``. A run killed outright
(SIGKILL, power loss) still says ``running`` but its process is gone and nobody holds its
lock: :func:`run_state` reports it as ``cut``, so nothing mistakes it for a finished run.
"""

from __future__ import annotations

import json
import signal
from collections.abc import Callable
from pathlib import Path
from typing import Any

from flowrun.errors import TrainingError
from flowrun.rundir.folders import Interrupted, read_status, write_json
from flowrun.rundir.lock import FolderLock
from flowrun.rundir.lock import is_locked as lock_held

LOCK_FILE = ".train.lock"
METRICS = "metrics.json"
STATUSES = ("running", "complete", "interrupted", "failed")


class RunLock(FolderLock):
    """An exclusive lock on a run folder while a process trains into it (``.train.lock``).

    The operating system releases it when the process ends, however it ends, so a killed run
    never leaves a stale lock.
    """

    def __init__(self, run_dir: Path) -> None:
        """Prepare the lock of ``run_dir`` (taken by :meth:`acquire` or ``with``)."""
        super().__init__(run_dir / LOCK_FILE, _busy_run(run_dir))


def _busy_run(run_dir: Path) -> Callable[[str], TrainingError]:
    def busy(holder: str) -> TrainingError:
        return TrainingError(
            f"{run_dir} is in use by another flowrun train (pid {holder}); "
            "wait for it to finish or stop it (Ctrl-C) before resuming"
        )

    return busy


def is_locked(run_dir: Path) -> bool:
    """Whether a live process holds ``run_dir``'s training lock."""
    return lock_held(run_dir / LOCK_FILE)


def read_metrics(run_dir: Path) -> dict[str, Any] | None:
    """``metrics.json`` of a run folder (``None`` when missing or unreadable)."""
    try:
        data = json.loads((run_dir / METRICS).read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def write_status(run_dir: Path, status: str, **fields: Any) -> None:
    """Write ``metrics.json`` with ``status`` and ``fields`` (atomically); ``partial`` says
    whether the numbers cover less than the whole run (any status but ``complete``)."""
    if status not in STATUSES:
        raise ValueError(f"status must be one of {STATUSES}, got {status!r}")
    write_json(run_dir / METRICS, {"status": status, "partial": status != "complete", **fields})


def run_state(run_dir: Path) -> str:
    """``complete``, ``interrupted``, ``failed``, ``running`` (a live process trains it) or
    ``cut`` (killed while training, or no status at all).

    ``status.json`` decides; folders written before it existed are judged by their
    ``metrics.json`` and lock.
    """
    shared = read_status(run_dir).state
    if shared != "unknown":
        return "running" if shared == "cut" and is_locked(run_dir) else shared
    metrics = read_metrics(run_dir)
    status = None if metrics is None else metrics.get("status")
    if status in ("complete", "interrupted", "failed"):
        return str(status)
    return "running" if is_locked(run_dir) else "cut"


class StopRequest:
    """Ctrl-C/SIGTERM received: the first asks to stop at the next step boundary (a
    checkpoint, finished logs), a second one stops at once (:class:`Interrupted`, a
    ``KeyboardInterrupt`` that knows its signal).

    Call it (``should_stop()``) to know whether a stop was asked; the CLI's signal handlers
    call :meth:`signal`.
    """

    def __init__(self) -> None:
        """No signal yet."""
        self.signum: int | None = None

    def __call__(self) -> bool:
        """Whether a stop was asked."""
        return self.signum is not None

    def signal(self, signum: int) -> None:
        """Record a signal; raise :class:`Interrupted` (a ``KeyboardInterrupt``) if one came
        before."""
        if self.signum is not None:
            raise Interrupted(self.signum)
        self.signum = signum

    def check(self) -> None:
        """Raise :class:`Interrupted` once a stop was asked (call between steps)."""
        if self.signum is not None:
            raise Interrupted(self.signum)

    @property
    def exit_code(self) -> int:
        """128 + the signal: 130 for Ctrl-C (SIGINT), 143 for SIGTERM."""
        return 128 + (self.signum if self.signum is not None else signal.SIGINT)
