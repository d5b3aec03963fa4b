"""Room for an actuated light's detectors on the lanes that approach it.

SUMO's actuated program puts one induction loop on every lane that has green in one of its
actuated phases (``minDur != maxDur``), ``d = min(detector-gap * speed limit,
(minDur / passing-time + 0.5) * 7.5 m)`` before the stop line (``minDur``: the shortest of those
phases; passing-time 1.9 s; 7.5 m: a car and its gap). On a lane shorter than ``d`` SUMO
silently moves the loop upstream (onto the junction before it) or to the lane's start, so the
program no longer measures the gaps it was given: flowrun refuses such a program instead.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from flowrun.config.traffic_lights import DETECTOR_GAP, Phase, TlsProgram
from flowrun.errors import ConfigError

#: SUMO's defaults: seconds a car needs to pass a detector, and a car's length with its gap, m.
PASSING_TIME, LENGTH_WITH_GAP = 1.9, 7.5


@dataclass(frozen=True)
class Approach:
    """A lane that enters a traffic light's junction.

    Attributes:
        lane_id: SUMO lane id.
        length: lane length, m.
        speed: lane speed limit, m/s.
        links: the light's link indices (state characters) that leave from this lane.
    """

    lane_id: str
    length: float
    speed: float
    links: tuple[int, ...]


def read_approaches(net_file: Path) -> dict[str, list[Approach]]:
    """The approach lanes of every traffic light of a SUMO network, by light id."""
    lanes: dict[str, tuple[float, float]] = {}
    links: dict[tuple[str, str], list[int]] = {}
    for _, elem in ET.iterparse(net_file, events=("end",)):
        if elem.tag == "lane":
            lanes[elem.get("id", "")] = (
                float(elem.get("length", "0")), float(elem.get("speed", "0"))
            )
        elif elem.tag == "connection" and elem.get("tl"):
            lane = f"{elem.get('from')}_{elem.get('fromLane')}"
            links.setdefault((elem.get("tl", ""), lane), []).append(int(elem.get("linkIndex", "0")))
        elif elem.tag == "edge":
            elem.clear()
    out: dict[str, list[Approach]] = {}
    for (tls, lane), indices in links.items():
        length, speed = lanes.get(lane, (0.0, 0.0))
        out.setdefault(tls, []).append(Approach(lane, length, speed, tuple(sorted(indices))))
    return out


def _actuated(phase: Phase) -> bool:
    """SUMO's test: the phase may last between different minimum and maximum durations."""
    low = phase.duration if phase.min_dur is None else phase.min_dur
    high = phase.duration if phase.max_dur is None else phase.max_dur
    return low != high


def detector_distance(detector_gap: float, speed: float, min_dur: float) -> float:
    """Where SUMO puts an actuated light's detector: metres before the stop line.

    Args:
        detector_gap: the program's ``detector-gap``, s.
        speed: the lane's speed limit, m/s.
        min_dur: the shortest ``minDur`` of the actuated phases that give the lane green, s.
    """
    return min(detector_gap * speed, (min_dur / PASSING_TIME + 0.5) * LENGTH_WITH_GAP)


def check_detector_room(programs: list[TlsProgram], net_file: Path) -> None:
    """Refuse an actuated program with an approach lane too short for its detector.

    Raises:
        ConfigError: names the light, the lane, its length and the distance needed, with
            the ways out (longer edges, a smaller ``detectorGap``, a static program).
    """
    actuated = [p for p in programs if p.tls_type == "actuated" and any(map(_actuated, p.phases))]
    if not actuated:
        return
    approaches = read_approaches(net_file)
    for program in actuated:
        gap = float(dict(program.params).get("detector-gap", DETECTOR_GAP))
        for lane in approaches.get(program.node_id, ()):
            greens = [
                p.min_dur if p.min_dur is not None else p.duration
                for p in program.phases
                if _actuated(p) and any(i < len(p.state) and p.state[i] in "Gg" for i in lane.links)
            ]
            if not greens:
                continue
            need = detector_distance(gap, lane.speed, min(greens))
            if lane.length < need:
                raise ConfigError(
                    f"actuated light {program.node_id!r} has no room for its detector on lane "
                    f"{lane.lane_id!r}: the lane is {lane.length:g} m long, the detector "
                    f"belongs {need:g} m before the stop line (detectorGap {gap:g} s x "
                    f"{lane.speed:g} m/s); use longer edges, a smaller detectorGap, or "
                    "tls_type static",
                    path=f"traffic_lights.{program.node_id}.tls_type",
                )
