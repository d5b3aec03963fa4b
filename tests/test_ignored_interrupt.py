"""A SIGTERM that lands where Python ignores exceptions (a ``__del__``, a garbage collector's
callback) still stops the work of ``sigterm_as_interrupt``, without a traceback on stderr."""

from __future__ import annotations

import os
import signal

import pytest

from flowrun.cli.common import sigterm_as_interrupt
from flowrun.rundir.folders import Interrupted


class _SignalsWhenCollected:
    def __del__(self) -> None:
        os.kill(os.getpid(), signal.SIGTERM)  # the handler runs here, inside __del__


def test_signal_inside_del_stops_at_the_end_of_the_work(capsys: pytest.CaptureFixture[str]) -> None:
    steps: list[int] = []
    with pytest.raises(Interrupted) as caught, sigterm_as_interrupt():
        obj = _SignalsWhenCollected()
        del obj  # Python prints and drops what __del__ raises
        steps.append(1)  # the work went on
    assert steps == [1]
    assert caught.value.exit_code == 143
    assert "Traceback" not in capsys.readouterr().err


def test_without_a_signal_the_work_ends_normally() -> None:
    with sigterm_as_interrupt():
        done = True
    assert done
