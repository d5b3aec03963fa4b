"""A sweep's points as Ray tasks (``flowrun sweep --backend ray`` / ``--ray-address``).

Each point is one Ray task that asks for one CPU and runs the point's ``flowrun baseline``
command -- the very command a local sweep runs -- in a child process of the Ray worker
(:class:`~flowrun.experiment.sweep_procs.PointProcess`). So a point's results do not depend on
where it ran, and a Ray worker never hosts a simulation itself: libsumo runs one simulation
per process, and each point gets a fresh process whatever Ray does with its workers (no need
for ``max_calls=1``, which would restart a worker per task).

The points write their run folders themselves, at the paths the driver gave: on one machine
that is where a local sweep writes them; on a cluster of several machines the config, the
working directory and ``--out`` must be on a file system every node mounts at the same path
(a task on a node that does not see the working directory fails with one line saying so).

Stopping: the driver keeps at most ``jobs`` tasks in flight. On Ctrl-C/SIGTERM it submits no
more and sets a stop flag (a tiny Ray actor) that each task polls: a running task passes the
signal on to its point (which finishes its log and labels its folder ``interrupted``), a task
that had not started its point returns at once. A second signal, or ``grace_s`` seconds,
cancels the tasks by force (their points then get SIGTERM from the kernel, as their parent
died). Finished points are kept; the same sweep run again skips them.

``import ray`` happens only inside the functions here.
"""

from __future__ import annotations

import os
import socket
import sys
import time
from collections.abc import Callable
from typing import Any

from flowrun.experiment.sweep import SweepPoint
from flowrun.experiment.sweep_procs import PointProcess

#: Seconds between two looks (driver: at the tasks; task: at its point and the stop flag).
POLL_S = 0.1
#: Exit code a task reports for a point it did not start because the sweep was stopping.
NOT_STARTED = -1


class StopFlag:
    """The signal number that stops the sweep (0 while it runs); a Ray actor on the cluster."""

    def __init__(self) -> None:
        self.signum = 0

    def set(self, signum: int) -> None:
        """Stop the sweep with ``signum`` (the first signal wins)."""
        self.signum = self.signum or signum

    def get(self) -> int:
        """The stop signal, or 0."""
        return self.signum


def run_point_task(args: list[str], cwd: str, flag: Any) -> tuple[int, str]:
    """Body of one point's Ray task: its command in a child process of this worker.

    Args:
        args: the point's command without the interpreter (this node's Python runs it).
        cwd: the driver's working directory (the relative paths of the command are from it).
        flag: the sweep's :class:`StopFlag` actor.

    Returns:
        The point's exit code and the last line of its stderr; :data:`NOT_STARTED` when the
        sweep was stopping before the point started.
    """
    import ray

    if not os.path.isdir(cwd):
        return 1, (
            f"error: the sweep's working directory {cwd} does not exist on Ray node "
            f"{socket.gethostname()}: run the sweep from a file system every node mounts "
            "at the same path (with the config and --out on it)"
        )
    if ray.get(flag.get.remote()):
        return NOT_STARTED, ""
    point = PointProcess([sys.executable, *args], cwd=cwd)
    passed_on = False
    try:
        while point.proc.poll() is None:
            signum = 0 if passed_on else ray.get(flag.get.remote())
            if signum:
                point.proc.send_signal(signum)
                passed_on = True
            time.sleep(POLL_S)
    except KeyboardInterrupt:  # ray.cancel or a Ctrl-C that reached the worker
        point.proc.kill()
    return point.result()


def run_points_on_ray(
    commands: list[tuple[SweepPoint, list[str]]],
    jobs: int,
    on_done: Callable[[SweepPoint, int, str], None],
    stop: list[int],
    grace_s: float,
    cwd: str | None = None,
) -> None:
    """Run the commands as Ray tasks on the connected cluster, at most ``jobs`` at a time.

    Ray must be initialised (:func:`flowrun.training.rllib.cluster.ray_session`).

    Args:
        commands: each point and its command (interpreter first; each node uses its own).
        jobs: tasks in flight at most.
        on_done: called with (point, exit code, last stderr line) as each point ends.
        stop: the signals received so far, appended to by the caller's signal handler; the
            loop stops at the first (see the module docstring).
        grace_s: seconds the running points get to finish their logs after a stop.
        cwd: the working directory of the points (default: this process's).
    """
    import ray

    actor: Any = ray.remote(num_cpus=0)(StopFlag)
    flag = actor.remote()
    task = ray.remote(num_cpus=1, max_retries=0)(run_point_task)
    where = cwd or os.getcwd()
    todo = list(commands)
    running: dict[Any, SweepPoint] = {}
    try:
        while (todo or running) and not stop:
            while todo and len(running) < jobs and not stop:
                point, cmd = todo.pop(0)
                running[task.remote(cmd[1:], where, flag)] = point
            _collect(ray, running, on_done, POLL_S)
        if stop:
            ray.get(flag.set.remote(stop[0]))
            deadline = time.monotonic() + grace_s
            while running:
                if len(stop) > 1 or time.monotonic() > deadline:
                    for ref in running:
                        ray.cancel(ref, force=True)
                _collect(ray, running, on_done, POLL_S)
    finally:
        ray.kill(flag)


def _collect(
    ray: Any,
    running: dict[Any, SweepPoint],
    on_done: Callable[[SweepPoint, int, str], None],
    timeout: float,
) -> None:
    """Wait up to ``timeout`` s for tasks to end; report and forget the ended ones."""
    if not running:
        return
    ready, _ = ray.wait(list(running), num_returns=len(running), timeout=timeout)
    for ref in ready:
        point = running.pop(ref)
        try:
            code, last = ray.get(ref)
        except ray.exceptions.RayError as err:  # the task's worker died or was cancelled
            text = str(err).strip()
            code, last = 1, f"Ray: {text.splitlines()[0] if text else type(err).__name__}"
        on_done(point, code, last)
