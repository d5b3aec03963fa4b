"""Write an output file so that it never overwrites anything and is never seen half-written.

The content goes to a hidden ``.<name>.<pid>.<random>.partial`` file beside the final path;
only when it is complete is it linked under the final name (a hard link fails if the name
exists, so a file created meanwhile is not overwritten either). An exception or an
interruption removes the partial file; a SIGKILL leaves it, recognisably named ``.partial``.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

from flowrun.errors import RecordingError

PARTIAL_SUFFIX = ".partial"


def _reason(err: OSError) -> str:
    return err.strerror or str(err)


def _publish(tmp: Path, dst: Path, what: str) -> None:
    """Give ``tmp`` the name ``dst`` unless ``dst`` exists."""
    try:
        os.link(tmp, dst)
    except FileExistsError:
        raise RecordingError(
            f"{dst} appeared while {what} was being written; nothing was overwritten "
            f"(choose another path)"
        ) from None
    except OSError:  # a file system without hard links: check, then rename
        if dst.exists():
            raise RecordingError(
                f"{dst} exists; choose a new path for {what} (nothing is overwritten)"
            ) from None
        os.replace(tmp, dst)
        return
    tmp.unlink()


@contextmanager
def new_file(dst: Path, what: str) -> Iterator[Path]:
    """Yield a temporary path to write ``what`` to; on success it becomes ``dst``.

    Args:
        dst: the final path; must not exist.
        what: a name for messages, e.g. ``"the --csv export"``.

    Raises:
        RecordingError: ``dst`` exists, its folder cannot be made or written, or writing
            failed (disk full, ...).
    """
    if dst.exists() or dst.is_symlink():
        raise RecordingError(f"{dst} exists; choose a new path for {what} (nothing is overwritten)")
    if dst.name in ("", ".", ".."):
        raise RecordingError(f"{dst} is not a file name; give {what} a file path")
    tmp = dst.parent / f".{dst.name}.{os.getpid()}.{secrets.token_hex(4)}{PARTIAL_SUFFIX}"
    # the name is this process's alone (pid + random), so the cleanup below may remove it
    # whatever happened: an interruption landing just after its creation included
    try:
        try:
            dst.parent.mkdir(parents=True, exist_ok=True)
            with open(tmp, "xb"):
                pass
        except OSError as err:
            raise RecordingError(f"cannot write {what} to {dst}: {_reason(err)}") from None
        try:
            yield tmp
        except OSError as err:
            raise RecordingError(
                f"writing {what} to {dst} failed: {_reason(err)}; nothing was written there"
            ) from None
        try:
            _publish(tmp, dst, what)
        except OSError as err:
            raise RecordingError(f"cannot write {what} to {dst}: {_reason(err)}") from None
    finally:
        with suppress(OSError):  # a folder that could not be made holds no partial file
            tmp.unlink()
