"""Queues, delays and signal colours per intersection approach, from a log's frames.

An *approach* of a traffic light is one edge whose cars the light controls: the
``<connection ... tl="LIGHT" linkIndex="i">`` elements of the ``network.net.xml`` the log
carries name each link's incoming edge. Per logged step and approach:

* **queue**: cars on the approach edge with speed < 0.1 m/s (the signal baselines' queue);
* **signal**: the approach's colour from the light's state string of that step: green if any
  of its links shows ``G``/``g``, else yellow if any shows ``y``/``Y``/``u``, else red
  (unknown where the log has no signal state for the step);
* **delay**: time lost against the speed limit by the cars on the approach edge,
  ``sum over cars of dt * max(0, 1 - v / v_limit)`` (vehicle-seconds), with ``v_limit`` the
  edge's speed limit and ``dt`` the simulated time since the previous logged step (the gap to
  the next one for the first step), so a thinned log (``--record-every``) estimates the same
  quantity.

An intersection's **mean delay** is its approaches' total delay divided by the number of
distinct cars seen on them (s per car), its **mean queue** the mean over logged steps of the
sum of its approaches' queues (cars).
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from flowrun.errors import RecordingError
from flowrun.recording import McapLog
from flowrun.replay.route import NET_ATTACHMENT, parse_net_xml
from flowrun.types import FloatArray, IntArray

#: Speed below which a car counts as queued, m/s (as ``flowrun.experiment.signal_baselines``).
QUEUE_SPEED = 0.1
UNKNOWN, RED, YELLOW, GREEN = -1, 0, 1, 2
_GREEN, _YELLOW = frozenset("Gg"), frozenset("yYu")


@dataclass(frozen=True)
class Approach:
    """One incoming edge of a traffic light.

    Attributes:
        edge: the edge id.
        links: indices of the light's links (state characters) that leave this edge.
        speed_limit: the edge's speed limit (its fastest lane), m/s.
    """

    edge: str
    links: tuple[int, ...]
    speed_limit: float


@dataclass(frozen=True)
class LightSeries:
    """One light's approaches over the logged steps (arrays: steps x approaches).

    Attributes:
        light: the light's id.
        approaches: its incoming edges, sorted by edge id.
        queue: queued cars per approach.
        signal: ``GREEN``/``YELLOW``/``RED`` (``UNKNOWN`` without a logged state).
        delay: vehicle-seconds lost per approach in the interval the step stands for.
        vehicles: distinct cars seen on the approaches.
    """

    light: str
    approaches: tuple[Approach, ...]
    queue: IntArray
    signal: npt.NDArray[np.int8]
    delay: FloatArray
    vehicles: int

    @property
    def mean_queue(self) -> float:
        """Mean over steps of the queued cars on all approaches."""
        return float(self.queue.sum(axis=1).mean()) if self.queue.size else float("nan")

    @property
    def max_queue(self) -> int:
        """Most queued cars on all approaches at one step."""
        return int(self.queue.sum(axis=1).max()) if self.queue.size else 0

    @property
    def mean_delay(self) -> float:
        """Total delay on the approaches per car seen on them, s."""
        return float(self.delay.sum()) / self.vehicles if self.vehicles else float("nan")


@dataclass(frozen=True)
class SignalSeries:
    """Every light's approaches over the logged steps.

    Attributes:
        time: simulation time of each logged step, s.
        dt: simulated time each logged step stands for, s.
        lights: one entry per light, sorted by light id.
    """

    time: FloatArray
    dt: FloatArray
    lights: tuple[LightSeries, ...]


def approaches(net_xml: bytes) -> dict[str, tuple[Approach, ...]]:
    """Each traffic light's approaches, from a SUMO ``.net.xml``.

    Raises:
        RecordingError: the bytes are not a SUMO network.
    """
    root = parse_net_xml(net_xml)
    limit: dict[str, float] = {}
    for edge in root.iter("edge"):
        speeds = [float(lane.get("speed", "0")) for lane in edge.iter("lane")]
        limit[edge.get("id", "")] = max(speeds, default=0.0)
    links: dict[str, dict[str, list[int]]] = defaultdict(lambda: defaultdict(list))
    for c in root.iter("connection"):
        tl, index = c.get("tl"), c.get("linkIndex")
        if tl is not None and index is not None:
            links[tl][c.get("from", "")].append(int(index))
    return {
        tl: tuple(
            Approach(edge, tuple(sorted(set(idx))), limit.get(edge, 0.0))
            for edge, idx in sorted(by_edge.items())
        )
        for tl, by_edge in sorted(links.items())
    }


def approach_colour(state: str, links: tuple[int, ...]) -> int:
    """``GREEN``/``YELLOW``/``RED`` of an approach from its light's state string."""
    chars = {state[i] for i in links if i < len(state)}
    if not chars:
        return UNKNOWN
    if chars & _GREEN:
        return GREEN
    if chars & _YELLOW:
        return YELLOW
    return RED


def _step_lengths(time: FloatArray) -> FloatArray:
    if time.size < 2:
        return np.ones_like(time)
    dt = np.diff(time, prepend=time[0] - (time[1] - time[0]))
    return np.asarray(dt, dtype=np.float64)


def signal_series(
    log: McapLog, start_s: float | None = None, end_s: float | None = None
) -> SignalSeries:
    """Queues, signal colours and delays per approach of every light (module docstring).

    Raises:
        RecordingError: the log has no traffic lights topic or no network attachment.
    """
    if not log.has_signals:
        raise RecordingError(
            f"{log.path} has no /flowrun/traffic_lights topic: it was logged on a network "
            "without traffic lights, or by a flowrun that did not log them"
        )
    net = log.attachments.get(NET_ATTACHMENT)
    if net is None:
        raise RecordingError(f"{log.path} has no {NET_ATTACHMENT} attachment to find approaches")
    by_light = approaches(net)
    names = sorted(by_light)
    flat = [(li, a) for li, name in enumerate(names) for a in by_light[name]]
    where = {a.edge: g for g, (_, a) in enumerate(flat)}
    owner = np.array([li for li, _ in flat], dtype=np.int64)
    limit = np.array([a.speed_limit for _, a in flat], dtype=np.float64)
    n = len(flat)
    states = {s.step: dict(zip(s.ids, s.states, strict=True)) for s in log.signals(start_s, end_s)}
    times: list[float] = []
    queue_rows: list[npt.NDArray[np.intp]] = []
    lost_rows: list[npt.NDArray[Any]] = []  # bincount with weights: float64
    colour_rows: list[list[int]] = []
    seen: list[set[str]] = [set() for _ in names]
    for msg in log.vehicle_messages(start_s, end_s):
        times.append(float(msg.time))
        idx = np.array([where.get(e, -1) for e in msg.edges], dtype=np.int64)
        on = idx >= 0
        g = idx[on]
        speed = np.array(msg.speed, dtype=np.float64)[on]
        queue_rows.append(np.bincount(g[speed < QUEUE_SPEED], minlength=n))
        v_max = limit[g]
        loss = np.where(v_max > 0, np.clip(1.0 - speed / np.where(v_max > 0, v_max, 1.0), 0, 1), 0)
        lost_rows.append(np.bincount(g, weights=loss, minlength=n))
        ids = list(msg.ids)
        for i in np.flatnonzero(on).tolist():
            seen[owner[where[msg.edges[i]]]].add(ids[i])
        step_states = states.get(int(msg.step), {})
        colour_rows.append(
            [approach_colour(step_states.get(names[li], ""), a.links) for li, a in flat]
        )
    time = np.array(times, dtype=np.float64)
    dt = _step_lengths(time)
    queue = np.array(queue_rows, dtype=np.int64).reshape(len(times), n)
    lost = np.array(lost_rows, dtype=np.float64).reshape(len(times), n) * dt[:, None]
    colour = np.array(colour_rows, dtype=np.int8).reshape(len(times), n)
    lights = []
    for li, name in enumerate(names):
        cols = np.flatnonzero(owner == li)
        lights.append(
            LightSeries(
                name, by_light[name], queue[:, cols], colour[:, cols], lost[:, cols], len(seen[li])
            )
        )
    return SignalSeries(time, dt, tuple(lights))


def intersection_rows(series: SignalSeries) -> list[dict[str, str]]:
    """The per-intersection table: one row per light (formatted for printing)."""
    return [
        {
            "light": s.light,
            "approaches": str(len(s.approaches)),
            "vehicles": str(s.vehicles),
            "mean queue": f"{s.mean_queue:.2f} veh",
            "max queue": str(s.max_queue),
            "mean delay": f"{s.mean_delay:.1f} s/veh",
        }
        for s in series.lights
    ]
