"""Run ``flowrun baseline`` processes, several at a time: the points of a sweep, the runs of
a benchmark. Each in its own session, so a Ctrl-C reaches the supervising command only, which
passes the signal on once to each running process (a second one, or a minute, kills them)."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any

from flowrun.cli.common import on_stop_signals
from flowrun.experiment.sweep import SweepPoint
from flowrun.experiment.sweep_procs import PointProcess
from flowrun.rundir.folders import Interrupted

#: Seconds between two looks at the running points.
POLL_S = 0.1
#: Seconds a point may take to finish its log after the signal before it is killed.
STOP_GRACE_S = 60.0


@contextmanager
def stop_requests() -> Iterator[list[int]]:
    """Ctrl-C/SIGTERM are noted (the signal number) for the supervising loop to act on."""
    received: list[int] = []

    def handler(signum: int, frame: Any) -> None:
        received.append(signum)

    with on_stop_signals(handler):
        yield received


class PointProcessJob(PointProcess):
    """One running point of a local sweep: the point and its process."""

    def __init__(self, point: SweepPoint, cmd: list[str]) -> None:
        super().__init__(cmd)
        self.point = point


def run_points(
    commands: list[tuple[SweepPoint, list[str]]],
    jobs: int,
    on_done: Callable[[SweepPoint, int, str], None],
) -> None:
    """Run the commands, at most ``jobs`` at a time; ``on_done(point, exit code, last line)``.

    Raises:
        Interrupted: Ctrl-C/SIGTERM came; the running points got the signal and finished.
    """
    todo = list(commands)
    running: list[PointProcessJob] = []
    with stop_requests() as stop:
        while (todo or running) and not stop:
            while todo and len(running) < jobs and not stop:
                point, cmd = todo.pop(0)
                running.append(PointProcessJob(point, cmd))
            for job in [j for j in running if j.proc.poll() is not None]:
                running.remove(job)
                on_done(job.point, *job.result())
            time.sleep(POLL_S)
        if stop:
            _stop(running, stop, on_done)
            raise Interrupted(stop[0])


def _stop(
    running: list[PointProcessJob], stop: list[int], on_done: Callable[[SweepPoint, int, str], None]
) -> None:
    """Pass the first signal on to the running points and wait for them to finish their logs;
    a second signal (or ``STOP_GRACE_S`` seconds) kills them."""
    for job in running:
        if job.proc.poll() is None:
            job.proc.send_signal(stop[0])
    deadline = time.monotonic() + STOP_GRACE_S
    while any(job.proc.poll() is None for job in running):
        if len(stop) > 1 or time.monotonic() > deadline:
            for job in running:
                if job.proc.poll() is None:
                    job.proc.kill()
        time.sleep(POLL_S)
    for job in running:
        on_done(job.point, *job.result())


def describe_points(what: str) -> Callable[[Mapping[str, Any]], str]:
    """The plain-text progress line of a pool of runs: what, and the last one finished."""

    def describe(fields: Mapping[str, Any]) -> str:
        last = fields.get("last")
        return f"{what} (last finished: {last})" if last else what

    return describe
