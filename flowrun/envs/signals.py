"""Pure pieces of the traffic-light envs: Flow's switch logic, signal states, edge numbers.

No SUMO here: :class:`SwitchTimers` is Flow's per-light bookkeeping (``last_change``,
``direction``, ``currently_yellow``) as arrays, testable with plain inputs.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from flowrun.types import BoolArray, FloatArray

#: per light, whether it is asked to switch (an array, or plain bools)
SwitchRequests = BoolArray | Sequence[bool]

_EDGE = re.compile(r"^(bot|top|left|right)(\d+)_(\d+)$")


def phase_state(vertical: Sequence[bool], direction: int, yellow: bool) -> str:
    """A light's state: green (or yellow) for one direction's links, red for the others.

    Args:
        vertical: per link (SUMO's link order), whether it comes from a vertical edge.
        direction: 0 = vertical traffic has green (Flow's ``GrGr``), 1 = horizontal.
        yellow: the green links show yellow instead (Flow's ``yryr`` / ``ryry``).
    """
    on = "y" if yellow else "G"
    return "".join(on if bool(v) == (direction == 0) else "r" for v in vertical)


@dataclass
class SwitchTimers:
    """Flow's switch logic of ``TrafficLightGridEnv`` for ``n`` lights.

    A light asked to switch (and not yellow) shows yellow for its current green links,
    restarts ``last_change`` and flips ``direction``; while yellow, ``last_change`` grows by
    ``dt`` per step and requests are ignored; once it reaches ``switch_time`` the new
    direction turns green. So every green -> red passes through ``switch_time`` s of yellow,
    and two switches start at least ``switch_time + dt`` s apart.

    Attributes:
        last_change: seconds since the last switch began (counted while yellow), per light.
        direction: 0 vertical green, 1 horizontal green, per light.
        currently_yellow: 1 while yellow, per light.
    """

    n: int
    switch_time: float
    dt: float
    last_change: FloatArray = field(init=False)
    direction: FloatArray = field(init=False)
    currently_yellow: FloatArray = field(init=False)
    #: ``last_change``, ``direction`` and ``currently_yellow`` in one array (the three
    #: attributes are views into it): what :meth:`features` copies
    packed: FloatArray = field(init=False)

    def __post_init__(self) -> None:
        self.packed = np.zeros(3 * self.n)
        self.last_change, self.direction, self.currently_yellow = (
            self.packed[: self.n], self.packed[self.n : 2 * self.n], self.packed[2 * self.n :]
        )

    def reset(self) -> None:
        """All lights vertical green, not yellow."""
        self.packed[:] = 0.0

    def step(self, switch: SwitchRequests) -> list[tuple[int, int, bool]]:
        """Advance one simulation step with the switch requests ``switch`` (per light).

        Returns:
            ``(light, direction, yellow)`` of each light whose state must change now.
        """
        # plain Python floats in the loop (the same IEEE arithmetic as the arrays', without
        # numpy's per-element cost), written back once
        last, direction, yellow = (
            self.last_change.tolist(), self.direction.tolist(), self.currently_yellow.tolist()
        )
        asked = switch.tolist() if isinstance(switch, np.ndarray) else list(switch)
        dt, switch_time = self.dt, self.switch_time
        changes = []
        for i, is_yellow in enumerate(yellow):
            if is_yellow == 1:
                last[i] += dt
                if last[i] >= switch_time:
                    yellow[i] = 0.0
                    changes.append((i, int(direction[i]), False))
            elif asked[i]:
                changes.append((i, int(direction[i]), True))  # yellow for the old green
                last[i] = 0.0
                direction[i] = 1 - direction[i]
                yellow[i] = 1.0
        self.last_change[:] = last
        if changes:
            self.direction[:] = direction
            self.currently_yellow[:] = yellow
        return changes

    def features(self) -> FloatArray:
        """``last_change``, ``direction`` and ``currently_yellow`` of all lights, concatenated."""
        return self.packed.copy()


def discrete_mask(action: int, n: int) -> BoolArray:
    """Flow's ``Discrete(2**n)`` action as per-light switch flags (light 0 = highest bit)."""
    bits = [int(b) for b in format(int(action), "b")][-n:] if n else []
    return np.array([0] * (n - len(bits)) + bits, dtype=bool)


def edge_number(edge: str, rows: int, cols: int) -> int:
    """Flow's number of a grid edge (``_convert_edge``): 0 for no edge; internal edges of
    ``center{k}`` come after all the others."""
    if not edge:
        return 0
    if edge.startswith(":"):
        digits = re.match(r":center(\d+)", edge)
        k = int(digits.group(1)) if digits else 0
        return (cols + 1) * rows * 2 + (rows + 1) * cols * 2 + k + 1
    m = _EDGE.match(edge)
    if m is None:
        return 0
    kind, row, col = m.group(1), int(m.group(2)), int(m.group(3))
    rows_below = 2 * (cols + 1) * row
    if kind in ("bot", "top"):
        num = rows_below + 2 * cols * (row + 1) + 2 * col + 1
        return num if kind == "bot" else num + 1
    num = rows_below + 2 * cols * row + 2 * col + 1
    return num if kind == "left" else num + 1


#: Flow's directions of ``_get_relative_node``, as (row step, column step)
_NEIGHBOUR_STEPS = {"top": (1, 0), "bottom": (-1, 0), "left": (0, -1), "right": (0, 1)}


def relative_node(node: int, direction: str, rows: int, cols: int) -> int:
    """Flow's ``_get_relative_node``: the index of the grid light next to light ``node`` in
    ``direction`` (``top``: the next row up, ``bottom``, ``left``, ``right``), lights numbered
    row by row from the bottom left (``center{row * cols + col}``); -1 at the grid's edge.

    Raises:
        NotImplementedError: an unknown direction (Flow's error type).
    """
    step = _NEIGHBOUR_STEPS.get(direction)
    if step is None:
        raise NotImplementedError(
            f"direction {direction!r}; expected one of: {', '.join(_NEIGHBOUR_STEPS)}"
        )
    row, col = divmod(node, cols)
    row, col = row + step[0], col + step[1]
    if not (0 <= row < rows and 0 <= col < cols):
        return -1
    return row * cols + col
