"""One sweep point as a child process: ``flowrun baseline`` with the point's options.

Each point runs in its own process (libsumo runs one simulation per process) and its own
session, so a terminal's Ctrl-C reaches the supervisor only (the local sweep, or the Ray task
of :mod:`flowrun.experiment.sweep_ray`), which passes the signal on once. On Linux the child
gets SIGTERM when its supervisor dies, even by SIGKILL, so no point runs on unsupervised: it
finishes its log and labels its folder ``interrupted``.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import tempfile
from typing import IO


def term_with_parent() -> None:
    """In the child: Ctrl-C/SIGTERM unblocked (a Ray worker blocks SIGINT, and a child
    inherits the mask), and on Linux, SIGTERM from the kernel when the parent dies."""
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    if sys.platform.startswith("linux"):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


class PointProcess:
    """A running point: its process and where its stderr goes.

    Args:
        cmd: the command (interpreter first).
        cwd: the working directory (``None``: this process's).
    """

    def __init__(self, cmd: list[str], cwd: str | None = None) -> None:
        self.stderr: IO[bytes] = tempfile.TemporaryFile()  # noqa: SIM115 - closed in result()
        self.proc = subprocess.Popen(
            cmd,
            cwd=cwd,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=self.stderr,
            start_new_session=True,  # a terminal's Ctrl-C reaches the supervisor, not the point
            preexec_fn=term_with_parent,
        )

    def result(self) -> tuple[int, str]:
        """Exit code and the last line of stderr (the point's one-line error)."""
        code = self.proc.wait()
        self.stderr.seek(0)
        lines = self.stderr.read().decode(errors="replace").strip().splitlines()
        self.stderr.close()
        return code, lines[-1] if lines else ""
