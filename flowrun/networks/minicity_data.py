"""Flow's mini city as data: nodes, edges, curved-edge arcs, forced lengths, connections.

Facts from Flow's ``flow/networks/minicity.py``: coordinates are in units of ``SCALING`` m
(40), every edge is Flow's ``edgeType`` (speed 30 m/s) with its own number of lanes, and a
curved edge follows an arc of a circle drawn with ``RESOLUTION`` points. An edge's length is
the distance between its nodes (straight) or the length of its arc polyline (curved), except
the edges in :data:`FORCED_LENGTHS`, which Flow shortens so that junctions do not overlap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: metres per unit of the coordinates below
SCALING = 40.0
#: points per curved edge (Flow's ``res``)
RESOLUTION = 40
#: speed limit of every edge (Flow's ``edgeType``), m/s
SPEED = 30.0

_PI = math.pi

#: Flow's nodes: id, x, y (units of SCALING)
NODES: tuple[tuple[str, float, float], ...] = (
    ("n_i1", 0.65, 2.75), ("n_i2", 0.65, 4.90), ("n_i3", 3.05, 2.75), ("n_i4", 3.05, 4.90),
    ("n_i5", 3.05, 5.75), ("n_i6", 5.08, 2.75), ("n_i7", 5.08, 3.75), ("n_i8", 5.08, 4.90),
    ("n_i9", 5.08, 5.75), ("n_r1", 0.30, 1.15), ("n_r2", 0.90, 0.40), ("n_r3", 0.95, 1.45),
    ("n_r4", 1.30, 1.13),
    ("n_r4_tmp", 1.83 - 0.53 * math.cos(0.2 * _PI), 0.94 - 0.53 * math.sin(0.2 * _PI)),
    ("n_r5", 4.55, 1.15), ("n_r6", 4.85, 1.60), ("n_r7", 5.10, 0.64), ("n_r8", 5.35, 1.60),
    ("n_b1", 0.65, 3.70), ("n_b2", 0.65, 4.20), ("n_b3", 3.05, 3.75), ("n_b4", 3.05, 4.20),
    ("n_b5", 4.10, 2.75), ("n_b6", 4.55, 2.75), ("n_m1_u", 1.83, 0.40), ("n_m1_b", 1.83, 0.40),
    ("n_m2", 1.96, 2.75), ("n_m3", 2.18, 4.90), ("n_m4", 2.50, 0.40), ("n_m5", 4.20, 4.90),
    ("n_s1", 0.65, 1.80), ("n_s2", 1.35, 4.07), ("n_s3", 1.67, 4.52), ("n_s4", 2.34, 1.14),
    ("n_s5", 2.34, 1.98), ("n_s6", 3.05, 1.15), ("n_s7_l", 3.51, 0.40), ("n_s7_r", 3.95, 0.40),
    ("n_s8", 4.20, 4.30), ("n_s9", 5.08, 2.22), ("n_s10", 5.63, 4.30), ("n_s11", 5.63, 5.21),
    ("n_s12", 0.65, 5.25), ("n_s13", 1.20, 5.75), ("n_s14", 4.75, 3.75),
)  # fmt: skip

#: Flow's edges in Flow's order: id, from node, to node, lanes
EDGES: tuple[tuple[str, str, str, int], ...] = (
    ("e_1", "n_s1", "n_r1", 2), ("e_2", "n_i1", "n_s1", 2), ("e_3", "n_b1", "n_i1", 2),
    ("e_4", "n_b2", "n_b1", 2), ("e_5", "n_i2", "n_b2", 1), ("e_6", "n_s12", "n_i2", 1),
    ("e_7", "n_r1", "n_r2", 2), ("e_8_b", "n_r2", "n_r4_tmp", 2),
    ("e_8_u", "n_r4_tmp", "n_r4", 2), ("e_9", "n_r4", "n_r3", 2), ("e_10", "n_r3", "n_s1", 2),
    ("e_11", "n_s1", "n_i1", 2), ("e_12", "n_i1", "n_b1", 2), ("e_13", "n_b1", "n_b2", 2),
    ("e_14", "n_b2", "n_i2", 1), ("e_15", "n_i2", "n_s12", 1), ("e_16", "n_s12", "n_s13", 1),
    ("e_17", "n_r2", "n_m1_b", 2), ("e_18", "n_b1", "n_s2", 1), ("e_19", "n_s2", "n_s3", 1),
    ("e_20", "n_s13", "n_i5", 1), ("e_21", "n_m1_u", "n_r4_tmp", 2),
    ("e_22", "n_i2", "n_m3", 1), ("e_23", "n_m3", "n_i2", 1), ("e_24", "n_s3", "n_m3", 1),
    ("e_25", "n_i1", "n_m2", 2), ("e_26", "n_m2", "n_i1", 2), ("e_27", "n_s13", "n_s12", 1),
    ("e_28_b", "n_m1_b", "n_m4", 2), ("e_29_u", "n_m4", "n_m1_u", 2),
    ("e_30", "n_m2", "n_s5", 1), ("e_31", "n_s5", "n_s4", 1), ("e_32", "n_s4", "n_m1_u", 1),
    ("e_33", "n_m3", "n_i4", 1), ("e_34", "n_i4", "n_m3", 1), ("e_35", "n_i5", "n_s13", 1),
    ("e_36", "n_m4", "n_s7_l", 2), ("e_37", "n_s6", "n_m4", 2), ("e_38", "n_s6", "n_i3", 2),
    ("e_39", "n_i3", "n_s6", 2), ("e_40", "n_i3", "n_b3", 2), ("e_41", "n_b3", "n_i3", 2),
    ("e_42", "n_b3", "n_b4", 2), ("e_43", "n_b4", "n_b3", 2), ("e_44", "n_b4", "n_i4", 1),
    ("e_45", "n_i4", "n_b4", 1), ("e_46", "n_i4", "n_i5", 1), ("e_47", "n_i5", "n_i4", 1),
    ("e_48", "n_i5", "n_i9", 1), ("e_49", "n_i4", "n_m5", 1), ("e_50", "n_i3", "n_b5", 2),
    ("e_51", "n_s7_l", "n_m4", 2), ("e_52", "n_s7_l", "n_s6", 2),
    ("e_53", "n_s7_r", "n_r7", 2), ("e_54", "n_b5", "n_i3", 2), ("e_55", "n_m5", "n_s8", 1),
    ("e_56", "n_s8", "n_s14", 1), ("e_57", "n_s8", "n_m5", 1), ("e_58", "n_m5", "n_i8", 1),
    ("e_59", "n_m5", "n_i4", 1), ("e_60", "n_b5", "n_b6", 2), ("e_61", "n_b6", "n_b5", 2),
    ("e_62", "n_s14", "n_s8", 1), ("e_63", "n_r5", "n_s7_r", 2), ("e_64", "n_r7", "n_r8", 2),
    ("e_65", "n_r8", "n_r6", 2), ("e_66", "n_r6", "n_r5", 2), ("e_67", "n_r8", "n_s9", 1),
    ("e_68", "n_s9", "n_r6", 1), ("e_69", "n_b6", "n_i6", 1), ("e_70", "n_i6", "n_b6", 1),
    ("e_71", "n_s9", "n_i6", 1), ("e_72", "n_i6", "n_s9", 1), ("e_73", "n_i6", "n_i7", 1),
    ("e_74", "n_i7", "n_i6", 1), ("e_75", "n_i7", "n_i8", 1), ("e_76", "n_i8", "n_i7", 1),
    ("e_77", "n_i8", "n_i9", 1), ("e_78", "n_i9", "n_i8", 1), ("e_79", "n_i9", "n_i5", 1),
    ("e_80", "n_i7", "n_s10", 1), ("e_81", "n_i9", "n_s11", 1), ("e_82", "n_s11", "n_i9", 1),
    ("e_83", "n_s10", "n_s11", 1), ("e_84", "n_s11", "n_s10", 1), ("e_85", "n_s10", "n_i7", 1),
    ("e_86", "n_i8", "n_m5", 1), ("e_87", "n_m2", "n_i3", 2), ("e_88", "n_i3", "n_m2", 2),
    ("e_89", "n_s14", "n_i7", 1), ("e_90", "n_i7", "n_s14", 1), ("e_91", "n_r5", "n_r7", 2),
    ("e_92", "n_r3", "n_r1", 2), ("e_93", "n_s7_l", "n_s7_r", 2),
    ("e_94", "n_s7_r", "n_s7_l", 2),
)  # fmt: skip


@dataclass(frozen=True)
class Arc:
    """A curved edge: ``(cx + sx*r*cos t, cy + sy*r*sin t)`` for ``t`` from ``t0`` to ``t1``
    (``cos`` and ``sin`` swapped if ``swap``; the points in reverse order if ``reverse``),
    in units of :data:`SCALING`."""

    cx: float
    cy: float
    r: float
    t0: float
    t1: float
    reverse: bool = False
    sx: float = 1.0
    sy: float = 1.0
    swap: bool = False

    def points(self, resolution: int = RESOLUTION) -> np.ndarray:
        """The shape, ``(resolution, 2)`` points in units of :data:`SCALING`."""
        t = np.linspace(self.t0, self.t1, resolution)
        if self.reverse:
            t = t[::-1]
        c, s = (np.sin(t), np.cos(t)) if self.swap else (np.cos(t), np.sin(t))
        return np.column_stack((self.cx + self.sx * self.r * c, self.cy + self.sy * self.r * s))


_R8 = 2.58 / 0.58  # angle offset of the east roundabout's arcs
#: Flow's curved edges
ARCS: dict[str, Arc] = {
    "e_1": Arc(-0.38, 1.80, 1.03, 2 * _PI, 2 * _PI - 0.56 / 1.03),
    "e_7": Arc(0.90, 0.93, 0.53, 3 * _PI / 2 - 1.16 / 0.53, 3 * _PI / 2),
    "e_8_b": Arc(0.90, 0.93, 0.53, 3 * _PI / 2, 1.8 * _PI),
    "e_8_u": Arc(0.90, 0.93, 0.53, 0.0, 1.16 / 0.53 - _PI / 2),
    "e_9": Arc(0.90, 0.93, 0.53, 3 * _PI / 2 + 1.16 / 0.53, 3 * _PI / 2 + 1.46 / 0.53),
    "e_10": Arc(1.08, 1.90, 0.43, _PI, _PI + 0.50 / 0.43, reverse=True),
    "e_16": Arc(1.19, 5.21, 0.54, _PI / 2, _PI, reverse=True),
    "e_18": Arc(1.11, 3.61, 0.46, 0.65 / 0.46, _PI, reverse=True),
    "e_19": Arc(1.21, 4.53, 0.46, 2 * _PI - 0.78 / 0.46, 2 * _PI),
    "e_21": Arc(1.89, 0.94, 0.54, 1.25 * _PI, 3 * _PI / 2, reverse=True),
    "e_24": Arc(2.13, 4.44, 0.46, _PI / 2, _PI, reverse=True),
    "e_27": Arc(1.19, 5.21, 0.54, _PI / 2, _PI),
    "e_30": Arc(1.88, 2.29, 0.46, 0.0, _PI / 2, reverse=True),
    "e_32": Arc(1.88, 0.86, 0.46, 3 * _PI / 2, 2 * _PI, reverse=True),
    "e_37": Arc(2.59, 0.86, 0.46, 3 * _PI / 2, 2 * _PI, reverse=True),
    "e_52": Arc(3.51, 0.86, 0.46, _PI, 3 * _PI / 2, reverse=True),
    "e_53": Arc(3.95, 4.39 - 0.15, 3.84, 3 * _PI / 2 - 0.1 / 3.84, 3 * _PI / 2 + 1.3 / 3.84),
    "e_56": Arc(4.75, 4.29, 0.54, 0.0, _PI / 2, sx=-1.0, sy=-1.0),
    "e_62": Arc(4.75, 4.29, 0.54, 0.0, _PI / 2, sx=-1.0, sy=-1.0, swap=True),
    "e_63": Arc(3.95, 1.03, 0.63, 3 * _PI / 2, 2 * _PI, reverse=True),
    "e_64": Arc(5.08, 1.17, 0.58, 3 * _PI / 2, _PI + _R8),
    "e_65": Arc(5.08, 1.17, 0.58, _PI + _R8, 1.2 * _PI + _R8),
    "e_66": Arc(5.08, 1.17, 0.58, 1.2 * _PI + _R8, 1.66 * _PI + _R8),
    "e_67": Arc(5.75, 2.23, 0.67, _PI, _PI + 0.64 / 0.67, reverse=True),
    "e_68": Arc(4.51, 2.27, 0.57, -0.42 / 0.57, 0.0, reverse=True),
    "e_80": Arc(5.08, 4.29, 0.54, -_PI / 2, 0.0),
    "e_81": Arc(5.08, 5.21, 0.54, _PI / 2, _PI, sx=-1.0),
    "e_82": Arc(5.08, 5.21, 0.54, 0.0, _PI / 2),
    "e_85": Arc(5.08, 4.29, 0.54, 0.0, _PI / 2, sy=-1.0),
    "e_91": Arc(5.08, 1.17, 0.58, 1.08 * _PI, 1.60 * _PI),
    "e_92": Arc(0.90, 0.93, 0.53, 3 * _PI / 2 + 1.46 / 0.53, 3.46 * _PI / 2 + 1.46 / 0.53),
}

#: Flow's forced lengths, m ("fix junction overlapping issue")
FORCED_LENGTHS: dict[str, float] = {
    "e_8_b": 2, "e_17": 18, "e_8_u": 8, "e_1": 9.9, "e_29_u": 13, "e_21": 5, "e_91": 5,
    "e_63": 26, "e_65": 5, "e_66": 30, "e_32": 12, "e_51": 8, "e_37": 5, "e_52": 5,
    "e_18": 12, "e_24": 12, "e_13": 10, "e_4": 10, "e_36": 8, "e_53": 49,
}  # fmt: skip

#: Flow's explicit lane connections: from edge, to edge, from lane, to lane. Two-lane edges
#: narrowing to one lane (both lanes into lane 0), the roundabouts' lane-keeping exits,
#: one lane of ``e_68`` into lane 0 of ``e_66``, and the turns at ``n_m4`` / ``n_s7_l`` /
#: ``n_s7_r`` that replace the U-turns netconvert would add there.
CONNECTIONS: tuple[tuple[str, str, int, int], ...] = (
    *((a, b, i, i // 2) for a, b in (("e_13", "e_14"), ("e_42", "e_44"), ("e_60", "e_69"))
      for i in range(2)),
    *((a, b, i, i) for a, b in (("e_66", "e_91"), ("e_66", "e_63"), ("e_7", "e_17"),
                                ("e_7", "e_8_b"), ("e_9", "e_10"), ("e_9", "e_92"))
      for i in range(2)),
    ("e_68", "e_66", 0, 0),
    *((a, b, i, i) for a, b in (("e_37", "e_29_u"), ("e_51", "e_29_u"), ("e_94", "e_52"),
                                ("e_94", "e_51"), ("e_36", "e_93"))
      for i in range(2)),
)  # fmt: skip
