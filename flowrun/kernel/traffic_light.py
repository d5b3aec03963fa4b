"""Flow's ``k.traffic_light``: every signal's state, read once per step, and commands.

The getters read the per-step snapshot (state string, phase index, program id, time of the
next switch) taken after each simulation step, as ``k.vehicle``'s do. ``set_state`` sends
the new state to SUMO at once (Flow's ``setRedYellowGreenState`` / ``setLinkState``) and
updates the snapshot, so a getter sees what SUMO will show in the next step.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from flowrun.suggest import did_you_mean

#: SUMO's signal characters.
_STATE_CHARS = frozenset("rRyYgGuoOs")


class TrafficLightKernel:
    """The traffic lights of the running simulation (Flow's ``TrafficLight`` kernel)."""

    def __init__(self) -> None:
        self.api: Any = None
        self._ids: list[str] = []
        self._index: dict[str, int] = {}
        self._links: list[list[tuple[str, str, str]]] = []
        self.states: list[str] = []
        self.phases = np.zeros(0, dtype=np.int64)
        self.next_switch = np.zeros(0)
        self.programs: list[str] = []
        self.time = 0.0

    # ------------------------------------------------------------------ kernel side
    def attach(self, api: Any) -> None:
        """Bind to a started simulation, list its lights and read their first state."""
        self.api = api
        tl = api.trafficlight
        self._ids = list(tl.getIDList())
        self._index = {t: i for i, t in enumerate(self._ids)}
        self._links = []
        for t in self._ids:
            links = tl.getControlledLinks(t)
            self._links.append([tuple(group[0]) if group else ("", "", "") for group in links])
        n = len(self._ids)
        self.states = [""] * n
        self.programs = [""] * n
        self.phases = np.zeros(n, dtype=np.int64)
        self.next_switch = np.zeros(n)
        self._get_state = tl.getRedYellowGreenState
        self._get_phase = tl.getPhase
        self._get_program = tl.getProgram
        self._get_next = tl.getNextSwitch
        self._get_time = api.simulation.getTime
        self.update()

    def update(self) -> None:
        """Read every light's state, phase, program and next switch time (once per step)."""
        if not self._ids:
            self.time = float(self._get_time()) if self.api is not None else 0.0
            return
        self.time = float(self._get_time())
        gs, gp, gpr, gn = self._get_state, self._get_phase, self._get_program, self._get_next
        for i, t in enumerate(self._ids):
            self.states[i] = gs(t)
            self.phases[i] = gp(t)
            self.programs[i] = gpr(t)
            self.next_switch[i] = gn(t)

    def _row(self, node_id: str) -> int:
        row = self._index.get(node_id)
        if row is None:
            known = ", ".join(self._ids) if self._ids else "none"
            raise KeyError(
                f"no traffic light {node_id!r}{did_you_mean(node_id, self._ids)}; lights: {known}"
            )
        return row

    # ------------------------------------------------------------------ Flow's getters
    def get_ids(self) -> list[str]:
        """Ids of all traffic lights (their junctions' ids)."""
        return list(self._ids)

    def get_state(self, node_id: str) -> str:
        """The light's state string: one character per controlled link (``G``, ``y``, ``r``...)."""
        return self.states[self._row(node_id)]

    def get_phase(self, node_id: str) -> int:
        """Index of the current phase in the running program."""
        return int(self.phases[self._row(node_id)])

    def get_program(self, node_id: str) -> str:
        """Id of the running program (``online`` after :meth:`set_state`)."""
        return self.programs[self._row(node_id)]

    def get_next_switch(self, node_id: str) -> float:
        """Simulation time of the next phase switch, s."""
        return float(self.next_switch[self._row(node_id)])

    def get_time_to_switch(self, node_id: str) -> float:
        """Seconds until the next phase switch."""
        return self.get_next_switch(node_id) - self.time

    def num_links(self, node_id: str) -> int:
        """Number of links (state characters) the light controls."""
        return len(self._links[self._row(node_id)])

    def get_controlled_links(self, node_id: str) -> list[tuple[str, str, str]]:
        """``(incoming lane, outgoing lane, via lane)`` of each link, in state order."""
        return list(self._links[self._row(node_id)])

    def get_controlled_lanes(self, node_id: str) -> list[str]:
        """The incoming lane of each link, in state order."""
        return [link[0] for link in self._links[self._row(node_id)]]

    # ------------------------------------------------------------------ commands
    def set_state(self, node_id: str, state: str, link_index: int | str = "all") -> None:
        """Set the light's state (``link_index="all"``) or one link's signal character.

        Raises:
            KeyError: unknown light.
            ValueError: a state of the wrong length or with unknown characters.
        """
        row = self._row(node_id)
        n = len(self._links[row])
        bad = sorted(set(state) - _STATE_CHARS)
        if bad:
            raise ValueError(f"unknown signal character(s) {bad} in {state!r} for {node_id!r}")
        tl = self.api.trafficlight
        if link_index == "all":
            if len(state) != n:
                raise ValueError(
                    f"state {state!r} has {len(state)} characters; light {node_id!r} "
                    f"controls {n} links"
                )
            tl.setRedYellowGreenState(node_id, state)
            self.states[row] = state
        else:
            index = int(link_index)
            if len(state) != 1 or not 0 <= index < n:
                raise ValueError(
                    f"set_state with link_index={link_index!r} needs one character and an "
                    f"index in [0, {n}), got {state!r}"
                )
            tl.setLinkState(node_id, index, state)
            current = self.states[row]
            self.states[row] = current[:index] + state + current[index + 1 :]
        self.programs[row] = "online"

    def set_program(self, node_id: str, program_id: str) -> None:
        """Switch the light to one of its loaded programs."""
        self._row(node_id)
        self.api.trafficlight.setProgram(node_id, program_id)
        self.programs[self._row(node_id)] = program_id
