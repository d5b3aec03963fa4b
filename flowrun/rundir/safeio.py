"""Files a run writes: strict JSON written atomically, file-system errors in one line."""

from __future__ import annotations

import errno
import json
import math
import os
from contextlib import suppress
from pathlib import Path
from typing import Any

#: ``errno`` values that mean the run folder cannot take more data.
WRITE_ERRORS = frozenset(
    {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS, errno.EACCES, errno.EPERM}
)


def describe_os_error(err: OSError) -> str:
    """One line for a file-system error, naming the likely cause."""
    hints = {
        errno.ENOSPC: "disk full",
        errno.EDQUOT: "disk quota exceeded",
        errno.EFBIG: "file too large (file size limit reached)",
        errno.EROFS: "read-only file system",
        errno.EACCES: "permission denied",
        errno.EPERM: "permission denied",
        errno.ENOTDIR: "a file is in the way of a folder",
    }
    what = hints.get(err.errno or 0, err.strerror or str(err))
    where = f" ({err.filename})" if err.filename else ""
    return f"{what}{where}"


def json_safe(data: Any) -> Any:
    """``data`` with every NaN and infinity replaced by ``None`` (JSON has neither)."""
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {k: json_safe(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [json_safe(v) for v in data]
    return data


def json_text(data: Any) -> str:
    """``data`` as strict, sorted, indented JSON (NaN/inf as null), newline-terminated."""
    text = json.dumps(json_safe(data), indent=2, sort_keys=True, default=str, allow_nan=False)
    return text + "\n"


def write_json(path: Path, data: Any, reserve: int = 0) -> None:
    """Write strict JSON atomically (a reader never sees half a file; NaN/inf become null).

    Args:
        path: the file.
        data: what to write.
        reserve: pad the file with spaces to at least this many bytes (room to overwrite it
            in place later, when the disk may be full).

    Raises:
        OSError: the file cannot be written (the temporary file is removed).
    """
    text = json_text(data)
    text += " " * max(0, reserve - len(text.encode()))
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with tmp.open("w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        tmp.replace(path)
    except BaseException:
        with suppress(OSError):
            tmp.unlink()
        raise
