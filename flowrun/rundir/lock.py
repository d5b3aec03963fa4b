"""An exclusive lock on a folder for one process (``flock`` on a lock file in it).

The operating system releases it when the process ends, however it ends, so a killed process
never leaves a stale lock; the file holds the holder's pid for the error message.
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Callable
from pathlib import Path
from types import TracebackType

from flowrun.errors import FlowrunError


class FolderLock:
    """Hold ``path`` (a lock file) exclusively.

    Args:
        path: the lock file (created if missing; its folder must exist).
        busy: the error to raise when another process holds it, given the holder's pid.
    """

    def __init__(self, path: Path, busy: Callable[[str], FlowrunError]) -> None:
        self.path = path
        self._busy = busy
        self._fd: int | None = None

    def acquire(self) -> FolderLock:
        """Take the lock, or raise ``busy(pid of the holder)``."""
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise self._busy(holder) from None
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd = fd
        return self

    def release(self) -> None:
        """Release the lock (idempotent)."""
        if self._fd is not None:
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> FolderLock:
        """Acquire."""
        return self.acquire()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Release."""
        self.release()


def is_locked(path: Path) -> bool:
    """Whether a live process holds the lock file ``path``."""
    if not path.is_file():
        return False
    fd = os.open(path, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False
