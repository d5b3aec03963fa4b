"""``flowrun replay LOG --html OUT.html``: one self-contained file that plays a run in a browser.

The page (``player.html`` beside this module) holds its data inline: the road (lane shapes
of the log's ``network.net.xml``, a circle for the numpy ring), one entry per vehicle, and per
logged step compact columns (vehicle, x/y in 0.1 m steps, heading, speed, leader, headway:
12 bytes a car, base64 in the page). No server and no network access: open the file.

Runs larger than :data:`BUDGET_BYTES` of car data are thinned to every k-th logged step, and
the page and :class:`HtmlReport` say so. A log without geometry plays the cars without a road
and the page says what it cannot draw.
"""

from __future__ import annotations

import base64
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.errors import RecordingError
from flowrun.recording import McapLog
from flowrun.recording.atomic import new_file
from flowrun.render import Road, ring_road, road_from_net_xml, speed_top
from flowrun.replay.summary import summarize, summary_rows

#: Car data (before base64) above which logged steps are thinned: keeps a page near 30 MB.
BUDGET_BYTES = 20_000_000
BYTES_PER_CAR = 12
PLAYER = Path(__file__).with_name("player.html")
NO_HEADWAY = 65535


@dataclass
class HtmlReport:
    """What :func:`write_html` wrote.

    Attributes:
        path: the page.
        bytes: its size.
        frames: logged steps in the page.
        stride: every how many logged steps one is kept (1: all).
        notes: what the page could not show (no geometry, thinned, damaged log).
    """

    path: Path
    bytes: int
    frames: int
    stride: int
    notes: list[str] = field(default_factory=list)


def log_road(log: McapLog) -> tuple[Road | None, str | None]:
    """The road of a log and, without one, why not."""
    net = log.attachments.get("network.net.xml")
    if net is not None:
        try:
            return road_from_net_xml(net), None
        except RecordingError as err:
            return None, f"the road is not drawn: the log's network.net.xml is unreadable ({err})"
    meta = log.metadata
    length = meta.get("network_length")
    if meta.get("backend") == "numpy" and length:
        return ring_road(float(length)), None
    return None, (
        "the road is not drawn: this log carries no network geometry (no network.net.xml "
        "attachment); cars are shown at their logged x/y"
    )


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def _stride(log: McapLog, start: float | None, end: float | None) -> int:
    """Every how many logged steps to keep so that the car data stays within the budget."""
    car_steps = sum(s.num_vehicles for s in log.stats(start, end))
    if not car_steps:  # no stats (damaged): estimate from the frame count
        car_steps = (log.frame_count or 0) * 200
    return max(1, math.ceil(car_steps * BYTES_PER_CAR / BUDGET_BYTES))


class _Columns:
    """The per-step car columns being collected."""

    def __init__(self) -> None:
        self.index: dict[str, int] = {}
        self.ids: list[str] = []
        self.types: list[str] = []
        self.rl: list[int] = []
        self.parts: dict[str, list[np.ndarray]] = {
            k: [] for k in ("vid", "x", "y", "ang", "spd", "lead", "hw")
        }
        self.counts: list[int] = []
        self.times: list[float] = []
        self.fastest = 0.0

    def vehicle(self, vid: str, vtype: str, rl: bool) -> int:
        i = self.index.get(vid)
        if i is None:
            i = self.index[vid] = len(self.ids)
            self.ids.append(vid)
            self.types.append(vtype)
            self.rl.append(int(rl))
        return i

    def add(self, frame: Any, heading: np.ndarray) -> None:
        n = len(frame.ids)
        rl = np.asarray(frame.is_rl, dtype=bool).tolist()
        vid = [self.vehicle(v, t, r) for v, t, r in zip(frame.ids, frame.types, rl, strict=True)]
        index = self.index
        lead = [index.get(v, -1) + 1 if v else 0 for v in frame.leader]
        speed = np.nan_to_num(np.asarray(frame.speed, dtype=np.float64))
        if n:
            self.fastest = max(self.fastest, float(speed.max()))
        hw = np.asarray(frame.headway, dtype=np.float64) * 10
        p = self.parts
        p["vid"].append(np.array(vid, dtype=np.int64))
        p["x"].append(np.asarray(frame.x, dtype=np.float64))
        p["y"].append(np.asarray(frame.y, dtype=np.float64))
        p["ang"].append(np.rint(np.nan_to_num(heading) / (2 * np.pi) * 256).astype(np.int64) % 256)
        p["spd"].append(speed)
        p["lead"].append(np.array(lead, dtype=np.int64))
        p["hw"].append(np.where(np.isfinite(hw) & (hw >= 0), np.minimum(hw, NO_HEADWAY - 1),
                                NO_HEADWAY).astype(np.int64))  # fmt: skip
        self.counts.append(n)
        self.times.append(float(frame.time))

    def pack(self, bounds: tuple[float, float, float, float]) -> dict[str, Any]:
        cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in self.parts.items()}
        x0, y0 = bounds[0], bounds[1]
        span = max(bounds[2] - x0, bounds[3] - y0, 1.0)
        q = max(0.1, span / 65000)  # m per unit
        top = speed_top(self.fastest)
        ids = np.uint16 if len(self.ids) < 65535 else np.uint32
        return {
            "times": self.times,
            "quant": {"x0": x0, "y0": y0, "q": q, "vq": top / 250},
            "top": top,
            "vehicles": {"ids": self.ids, "types": self.types, "rl": self.rl},
            "idBytes": np.dtype(ids).itemsize,
            "columns": {
                "off": _b64(np.concatenate(([0], np.cumsum(self.counts))).astype("<u4")),
                "vid": _b64(cat["vid"].astype(ids)),
                "x": _b64(np.clip(np.rint((cat["x"] - x0) / q), 0, 65535).astype("<u2")),
                "y": _b64(np.clip(np.rint((cat["y"] - y0) / q), 0, 65535).astype("<u2")),
                "ang": _b64(cat["ang"].astype(np.uint8)),
                "spd": _b64(np.clip(np.rint(cat["spd"] / (top / 250)), 0, 255).astype(np.uint8)),
                "lead": _b64(cat["lead"].astype(ids)),
                "hw": _b64(cat["hw"].astype("<u2")),
            },
        }


def _road_json(road: Road | None) -> dict[str, Any] | None:
    if road is None:
        return None
    return {
        "lanes": [
            [round(lane.width, 2), int(lane.internal), np.round(lane.shape, 2).ravel().tolist()]
            for lane in road.lanes
        ],
        "junctions": [np.round(j, 2).ravel().tolist() for j in road.junctions],
        "heads": [[round(h.x, 2), round(h.y, 2), h.light, h.link] for h in road.signals],
    }


def _lights(log: McapLog, times: list[float]) -> dict[str, Any]:
    """Signal states as changes: ``[frame index, light id, state]`` whenever one changes."""
    events: list[list[Any]] = []
    last: dict[str, str] = {}
    index = {t: i for i, t in enumerate(times)}
    for sig in log.signals(times[0], times[-1]):
        i = index.get(float(sig.time))
        if i is None:
            continue
        for light, state in zip(sig.ids, sig.states, strict=True):
            if last.get(light) != state:
                last[light] = state
                events.append([i, light, state])
    return {"events": events}


def player_data(
    log: McapLog,
    start: float | None = None,
    end: float | None = None,
    vehicles: list[str] | None = None,
) -> tuple[dict[str, Any], int]:
    """Everything the page shows, as one JSON-able dict, and the thinning stride (optionally
    the logged steps from ``start`` to ``end`` s and only some vehicles)."""
    road, missing = log_road(log)
    notes = [missing] if missing else []
    stride = _stride(log, start, end)
    cols = _Columns()
    for k, frame in enumerate(log.frames(start, end, vehicles)):
        if k % stride:
            continue
        if road is not None and len(frame.edges) == len(frame.ids):
            heading = road.headings(frame.edges, np.asarray(frame.lanes), frame.lane_pos,
                                    frame.x, frame.y)  # fmt: skip
        else:
            heading = np.zeros(len(frame.ids))
        cols.add(frame, heading)
    if not cols.times:
        raise RecordingError(f"{log.path} holds no logged step to play in the selection")
    if road is not None:
        bounds = road.bounds
    else:
        x = np.concatenate(cols.parts["x"]) if cols.parts["x"] else np.zeros(1)
        y = np.concatenate(cols.parts["y"]) if cols.parts["y"] else np.zeros(1)
        bounds = (float(x.min()) - 10, float(y.min()) - 10, float(x.max()) + 10,
                  float(y.max()) + 10)  # fmt: skip
    if stride > 1:
        notes.append(
            f"thinned: every {stride}th logged step is shown ({len(cols.times)} steps), "
            f"to keep this page near {BUDGET_BYTES * 4 // 3 // 10**6} MB"
        )
    if log.damage:
        notes.append(f"the log is damaged: {log.damage.short()}")
    data = cols.pack(bounds)
    data.update(
        title=log.path.name,
        notes=notes,
        headline={
            k: v
            for k, v in summary_rows(
                summarize(log, start_s=start, end_s=end, vehicles=vehicles)
            ).items()
            if not k.endswith("version")
        },
        bounds=list(bounds),
        road=_road_json(road),
        lights=_lights(log, cols.times),
        stride=stride,
    )
    return data, stride


def write_html(
    log: McapLog,
    out: Path,
    start: float | None = None,
    end: float | None = None,
    vehicles: list[str] | None = None,
) -> HtmlReport:
    """Write the player page of ``log`` to ``out`` (a new file; nothing half written),
    optionally of the logged steps from ``start`` to ``end`` s and only some vehicles.

    Raises:
        RecordingError: ``out`` exists, is a folder or cannot be written; the log holds no
            logged step.
    """
    if out.is_dir():
        raise RecordingError(f"--html {out} is a folder; give the new page's file name in it")
    if out.exists() or out.is_symlink():
        raise RecordingError(f"--html {out} exists; choose a new path (nothing is overwritten)")
    data, stride = player_data(log, start, end, vehicles)
    text = json.dumps(data, separators=(",", ":"), allow_nan=False)
    page = PLAYER.read_text(encoding="utf-8").replace(
        "/*FLOWRUN_DATA*/null", text.replace("</", "<\\/")
    )
    with new_file(out, "the --html page") as tmp:
        tmp.write_text(page, encoding="utf-8")
    return HtmlReport(out, out.stat().st_size, len(data["times"]), stride, data["notes"])
