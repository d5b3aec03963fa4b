"""``new_file``: an output appears whole under its name or not at all, even when an
interruption lands the moment its hidden partial file is created."""

from __future__ import annotations

import builtins
from pathlib import Path
from typing import Any

import pytest

from flowrun.errors import RecordingError
from flowrun.recording import atomic


def test_complete_write_appears_under_its_name_and_no_partial_stays(tmp_path: Path) -> None:
    dst = tmp_path / "out.csv"
    with atomic.new_file(dst, "the export") as tmp:
        tmp.write_text("a,b\n")
        assert not dst.exists()
    assert dst.read_text() == "a,b\n"
    assert list(tmp_path.iterdir()) == [dst]


def test_interrupt_right_after_the_partial_is_created_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def open_then_interrupt(path: Any, mode: str = "r", *args: Any, **kwargs: Any) -> Any:
        builtins.open(path, mode, *args, **kwargs).close()  # the file exists now
        raise KeyboardInterrupt

    monkeypatch.setattr(atomic, "open", open_then_interrupt, raising=False)
    with pytest.raises(KeyboardInterrupt), atomic.new_file(tmp_path / "out.csv", "the export"):
        pytest.fail("never reached: the interrupt lands before the body")
    assert list(tmp_path.iterdir()) == []


def test_folder_that_cannot_be_made_is_one_recording_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    with (
        pytest.raises(RecordingError, match="cannot write the export to"),
        atomic.new_file(blocker / "out.csv", "the export"),
    ):
        pass
    assert [p.name for p in tmp_path.iterdir()] == ["file"]
