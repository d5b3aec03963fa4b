"""What a long command tells while it works: its phases, its progress, and a closing line.

- :meth:`Feedback.phase` announces a step before it starts ("starting 2 environment
  processes", "final evaluation"), so no long step is silent.
- :meth:`Feedback.progress` shows a bar on a terminal; when the output is not a terminal
  (a pipe, ``nohup``, CI) it prints a plain line every :data:`PLAIN_EVERY_S` seconds instead,
  and nothing for a step shorter than that.
- :meth:`Feedback.close` prints the last line, with the command's total wall time.

Everything goes to the console (standard output); errors alone go to standard error.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any

from rich.console import Console
from rich.progress import Progress

#: Seconds between two plain-text progress lines when the output is not a terminal.
PLAIN_EVERY_S = 10.0

#: ``update(completed=..., total=..., **fields)``: what a command calls as it advances.
Update = Callable[..., None]


def duration(seconds: float) -> str:
    """``12.3 s``, ``3 min 25 s`` or ``1 h 02 min``."""
    if seconds < 60:
        return f"{seconds:.1f} s"
    minutes, secs = divmod(round(seconds), 60)
    if minutes < 60:
        return f"{minutes} min {secs:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


class Feedback:
    """A command's phases, progress and closing line (see the module doc).

    Args:
        console: where to print (the command's console).
        clock: seconds, monotonic (tests pass their own).
    """

    def __init__(self, console: Console, clock: Callable[[], float] = time.monotonic) -> None:
        self.console = console
        self.clock = clock
        self.started = clock()

    def elapsed(self) -> float:
        """Seconds since the command started."""
        return self.clock() - self.started

    def phase(self, text: str) -> None:
        """Announce a step about to start."""
        self.console.print(text, highlight=False, soft_wrap=True)

    def close(self, text: str) -> None:
        """The command's last line: ``text`` and the total wall time."""
        self.console.print(
            f"{text} (total {duration(self.elapsed())})", highlight=False, soft_wrap=True
        )

    @contextmanager
    def progress(
        self,
        columns: tuple[Any, ...],
        describe: Callable[[Mapping[str, Any]], str],
        total: float | None = None,
        **fields: Any,
    ) -> Iterator[Update]:
        """A progress display; yields ``update(completed=, total=, **fields)``.

        Args:
            columns: rich progress columns for the bar on a terminal.
            describe: the plain-text line (without the counts) from the current fields.
            total: the amount of work (``None``: not known yet).
            fields: the fields ``columns`` and ``describe`` read.
        """
        if self.console.is_terminal:
            with Progress(*columns, console=self.console, transient=True) as bar:
                task = bar.add_task("", total=total, **fields)

                def update_bar(
                    completed: float | None = None, total: float | None = None, **new: Any
                ) -> None:
                    bar.update(task, completed=completed, total=total, **new)

                yield update_bar
            return
        yield PlainProgress(self, describe, total, fields).update


class PlainProgress:
    """Progress as a plain line every :data:`PLAIN_EVERY_S` seconds (output not a terminal)."""

    def __init__(
        self,
        feedback: Feedback,
        describe: Callable[[Mapping[str, Any]], str],
        total: float | None,
        fields: dict[str, Any],
    ) -> None:
        self.feedback = feedback
        self.describe = describe
        self.total = total
        self.fields = fields
        self.completed = 0.0
        self.started = feedback.clock()
        self.last_line = self.started

    def update(
        self, completed: float | None = None, total: float | None = None, **new: Any
    ) -> None:
        """Record the new state; print a line when :data:`PLAIN_EVERY_S` passed since the
        last one."""
        if completed is not None:
            self.completed = completed
        if total is not None:
            self.total = total
        self.fields.update(new)
        now = self.feedback.clock()
        if now - self.last_line >= PLAIN_EVERY_S:
            self.last_line = now
            self.feedback.console.print(self.line(now - self.started), highlight=False)

    def line(self, elapsed: float) -> str:
        """``<describe>: 1200/6000 (20 %), 14.0 s``."""
        done = f"{self.completed:.0f}"
        if self.total:
            done += f"/{self.total:.0f} ({100 * self.completed / self.total:.0f} %)"
        return f"{self.describe(self.fields)}: {done}, {duration(elapsed)}"
