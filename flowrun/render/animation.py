"""A run as an animation: frames on one speed scale, written as a GIF and, where ``ffmpeg`` is
installed, an MP4."""

from __future__ import annotations

import logging
import shutil
import subprocess
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from flowrun.errors import FlowrunError
from flowrun.render.colours import speed_top
from flowrun.render.picture import FrameLike, Painter
from flowrun.render.road import Road

log = logging.getLogger(__name__)

RGB = npt.NDArray[np.uint8]


@dataclass(frozen=True)
class Snapshot:
    """One instant to draw: the cars and, on networks with lights, ``(ids, states)``."""

    frame: FrameLike
    signals: tuple[Sequence[str], Sequence[str]] | None = None


def cars_bounds(snapshots: Sequence[Snapshot]) -> tuple[float, float, float, float]:
    """The map area every car of ``snapshots`` was in (m; a 100 m square if none)."""
    xs = [np.asarray(s.frame.x) for s in snapshots if len(s.frame.x)]
    ys = [np.asarray(s.frame.y) for s in snapshots if len(s.frame.y)]
    if not xs:
        return -50.0, -50.0, 50.0, 50.0
    x, y = np.concatenate(xs), np.concatenate(ys)
    return float(x.min()) - 10, float(y.min()) - 10, float(x.max()) + 10, float(y.max()) + 10


def draw_run(
    road: Road | None,
    snapshots: Sequence[Snapshot],
    lengths: Mapping[str, float] | None = None,
    size: int = 720,
) -> list[RGB]:
    """Every snapshot as an RGB frame, all on the speed scale of the fastest car among them."""
    fastest = max((float(np.max(s.frame.speed)) for s in snapshots if len(s.frame.speed)),
                  default=0.0)  # fmt: skip
    bounds = road.bounds if road is not None else cars_bounds(snapshots)
    painter = Painter(road, speed_top(fastest), bounds=bounds, size=size, lengths=lengths)
    return [painter.draw(s.frame, s.signals) for s in snapshots]


@dataclass(frozen=True)
class Animation:
    """What :func:`write_animation` wrote: the GIF, the MP4 (or ``None``) and, without an
    MP4, one line saying why not."""

    gif: Path
    mp4: Path | None
    note: str | None


def write_gif(path: Path, frames: Sequence[RGB], fps: float = 10.0) -> None:
    """Write RGB frames as an animated GIF (one shared palette per frame, looping)."""
    from PIL import Image

    images = [Image.fromarray(f) for f in frames]
    if not images:
        raise FlowrunError(f"no frames to write to {path}")
    duration = max(20, round(1000 / fps))
    images[0].save(path, save_all=True, append_images=images[1:], duration=duration, loop=0)


def write_mp4(path: Path, frames: Sequence[RGB], fps: float, ffmpeg: str) -> str | None:
    """Encode frames to H.264 MP4 with ``ffmpeg``; returns why not on failure (no file left)."""
    h, w, _ = frames[0].shape
    cmd = [ffmpeg, "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24",
           "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-", "-pix_fmt", "yuv420p",
           "-c:v", "libx264", str(path)]  # fmt: skip
    try:
        proc = subprocess.run(cmd, input=b"".join(f.tobytes() for f in frames),
                              capture_output=True, check=False)  # fmt: skip
    except OSError as err:
        return f"ffmpeg could not be started ({err})"
    if proc.returncode != 0:
        path.unlink(missing_ok=True)
        first = proc.stderr.decode(errors="replace").strip().splitlines()
        return f"ffmpeg failed: {first[-1] if first else proc.returncode}"
    return None


def write_animation(stem: Path, frames: Sequence[RGB], fps: float = 10.0) -> Animation:
    """Write ``stem.gif`` and, where ``ffmpeg`` is on the PATH, ``stem.mp4``."""
    gif = stem.with_suffix(".gif")
    write_gif(gif, frames, fps)
    ffmpeg = shutil.which("ffmpeg")
    if ffmpeg is None:
        return Animation(gif, None, "no MP4: ffmpeg is not installed (e.g. apt-get install ffmpeg)")
    mp4 = stem.with_suffix(".mp4")
    why = write_mp4(mp4, frames, fps, ffmpeg)
    return Animation(gif, None if why else mp4, f"no MP4: {why}" if why else None)
