"""``status.json``: what became of a run, checked against the processes alive now.

A run folder says ``running`` (with pid, host and the process's start time) from its start and,
at its end, ``complete``, ``interrupted`` (with exit code 130/143) or ``failed`` (with the
error). :func:`read_status` answers ``cut`` for a folder still saying ``running`` whose process
is gone (killed, power cut), so nothing takes it for finished. The folder itself and
``tracked_run`` are in :mod:`flowrun.rundir.folders` (which re-exports these names).
"""

from __future__ import annotations

import json
import os
import signal
import socket
from contextlib import suppress
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from flowrun.rundir.safeio import json_text, write_json

STATUS_FILE = "status.json"
RUNNING, COMPLETE, INTERRUPTED, FAILED, CUT = "running", "complete", "interrupted", "failed", "cut"

#: ``status.json`` is written this big at the start (padded with spaces), so that its final
#: version can overwrite it in place when the disk is full.
STATUS_RESERVE = 2048


class Interrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM, stopping a run: a ``KeyboardInterrupt`` that knows its signal.

    Args:
        signum: the signal received (``SIGINT`` for a plain Ctrl-C).
    """

    def __init__(self, signum: int = signal.SIGINT) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)

    @property
    def exit_code(self) -> int:
        """The shell's code for death by this signal: 130 for SIGINT, 143 for SIGTERM."""
        return 128 + self.signum


def exit_code_of(err: BaseException) -> int:
    """Exit code for an interruption: 128 + signal (130 when the signal is unknown)."""
    return err.exit_code if isinstance(err, Interrupted) else 128 + signal.SIGINT


@dataclass(frozen=True)
class RunStatus:
    """What ``status.json`` says, checked against the processes alive now.

    Attributes:
        state: ``running``, ``complete``, ``interrupted``, ``failed``, ``cut`` (said running,
            but its process is gone) or ``unknown`` (no readable ``status.json``).
        pid: process that ran it.
        host: machine that ran it.
        started: UTC start time (ISO 8601).
        ended: UTC end time, when it ended.
        error: the one-line error of a failed run.
        exit_code: the command's exit code (130/143 when interrupted), when it ended.
    """

    state: str
    pid: int | None = None
    host: str | None = None
    started: str | None = None
    ended: str | None = None
    error: str | None = None
    exit_code: int | None = None

    @property
    def finished(self) -> bool:
        """Whether the run completed (its results are whole)."""
        return self.state == COMPLETE


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def _process_start(pid: int) -> str | None:
    """The kernel's start time of ``pid`` (Linux ``/proc``): tells a reused pid apart."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return stat.rsplit(")", 1)[-1].split()[19]  # field 22, counted after "pid (comm)"


def mark_running(run_dir: Path) -> None:
    """Write ``status.json``: ``running``, this process's pid, host and start time."""
    pid = os.getpid()
    write_json(
        run_dir / STATUS_FILE,
        {
            "status": RUNNING,
            "pid": pid,
            "pid_start": _process_start(pid),
            "host": socket.gethostname(),
            "started": _now(),
        },
        reserve=STATUS_RESERVE,
    )


def mark_done(
    run_dir: Path, state: str, *, error: str | None = None, exit_code: int | None = None
) -> None:
    """Replace ``running`` by how the run ended (``complete``, ``interrupted``, ``failed``)."""
    path = run_dir / STATUS_FILE
    data: dict[str, Any] = {}
    with suppress(OSError, ValueError):
        data = dict(json.loads(path.read_text()))
    data.update({"status": state, "ended": _now()})
    if error is not None:
        data["error"] = error
    if exit_code is not None:
        data["exit_code"] = exit_code
    try:
        write_json(path, data)
    except OSError:  # disk full: overwrite the reserved bytes of the running status instead
        text = json_text(data)
        if len(text.encode()) > STATUS_RESERVE:
            data["error"] = str(data.get("error", ""))[:500]
            text = json_text(data)
        raw = text.encode()
        with path.open("r+b") as f:
            size = f.seek(0, os.SEEK_END)
            f.seek(0)
            f.write(raw.ljust(size))  # same size or less: no new blocks needed
            f.truncate()
            f.flush()
            os.fsync(f.fileno())


def _alive(pid: int, start: str | None) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # someone else's process: it exists
    now = _process_start(pid)
    return start is None or now is None or now == start


def read_status(run_dir: Path) -> RunStatus:
    """How the run in ``run_dir`` ended, or ``cut`` if it says running but its process died."""
    try:
        data = json.loads((run_dir / STATUS_FILE).read_text())
        state = str(data["status"])
    except (OSError, ValueError, KeyError, TypeError):
        return RunStatus("unknown")
    pid = data.get("pid")
    host = data.get("host")
    here = isinstance(pid, int) and host == socket.gethostname()
    if state == RUNNING and here and not _alive(int(pid), data.get("pid_start")):
        state = CUT
    return RunStatus(
        state,
        pid=pid if isinstance(pid, int) else None,
        host=host,
        started=data.get("started"),
        ended=data.get("ended"),
        error=data.get("error"),
        exit_code=data.get("exit_code"),
    )


def is_complete(run_dir: Path) -> bool:
    """Whether ``run_dir`` holds a run that completed (not running, cut, interrupted, failed)."""
    return read_status(run_dir).finished
