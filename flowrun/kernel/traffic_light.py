"""Flow's ``k.traffic_light``: every signal's state, read once per step, and commands.

The getters read the per-step snapshot (state string, phase index, program id, time of the
next switch) of the current simulation step, as ``k.vehicle``'s do. The snapshot is taken when
first asked after a step (a step nobody asks about - an env that keeps its own signal
bookkeeping, recording off - reads nothing), and before any command of that step, so it is
the state SUMO showed right after the step. ``set_state`` sends the new state to SUMO at once
(Flow's ``setRedYellowGreenState`` / ``setLinkState``) and updates the snapshot, so a getter
sees what SUMO will show in the next step. A state longer than the light's links is cut to
them, with one warning naming the light and the ignored characters (SUMO ignores them too);
a shorter one is an error.

Flow's simulation runs from the env's construction, flowrun's from the first ``reset``: a
``set_state`` before that is kept and sent when the simulation starts (checked then), before
the env's ``reset`` sets its own initial signals.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from flowrun.suggest import did_you_mean

log = logging.getLogger(__name__)

#: SUMO's signal characters.
_STATE_CHARS = frozenset("rRyYgGuoOs")


class TrafficLightKernel:
    """The traffic lights of the running simulation (Flow's ``TrafficLight`` kernel)."""

    def __init__(self) -> None:
        self.api: Any = None
        self._ids: list[str] = []
        self._index: dict[str, int] = {}
        self._links: list[list[tuple[str, str, str]]] = []
        self._states: list[str] = []
        self._phases = np.zeros(0, dtype=np.int64)
        self._next_switch = np.zeros(0)
        self._programs: list[str] = []
        self._time = 0.0
        self._stale = False  # the snapshot is of an earlier step: read it when first asked
        self._valid_states: set[str] = set()  # state strings set_state has checked
        self._pinned: dict[int, list[Any]] = {}  # see _pin
        #: the network's lights before the simulation starts (see :meth:`expect`)
        self._expected: list[str] = []
        #: ``set_state`` calls made before the simulation started, sent when it starts
        self._pending: list[tuple[str, str, int | str]] = []
        self._warned: set[tuple[str, str]] = set()  # (light, state) warned as too long

    def expect(self, ids: list[str]) -> None:
        """The ids of the network's lights, known before the simulation starts: commands
        for them are kept until it does (Flow's simulation runs from the env's construction)."""
        self._expected = list(ids)

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
        self._states = [""] * n
        self._programs = [""] * n
        self._phases = np.zeros(n, dtype=np.int64)
        self._next_switch = np.zeros(n)
        # libsumo's compiled calls where there are (its Python wrappers add a call layer)
        raw = getattr(api, "_libsumo", None)
        if raw is not None and hasattr(raw, "trafficlight_getRedYellowGreenState"):
            self._get_state = raw.trafficlight_getRedYellowGreenState
            self._get_phase = raw.trafficlight_getPhase
            self._get_program = raw.trafficlight_getProgram
            self._get_next = raw.trafficlight_getNextSwitch
            self._get_time = raw.simulation_getTime
            self._set_state = raw.trafficlight_setRedYellowGreenState
        else:
            self._get_state = tl.getRedYellowGreenState
            self._get_phase = tl.getPhase
            self._get_program = tl.getProgram
            self._get_next = tl.getNextSwitch
            self._get_time = api.simulation.getTime
            self._set_state = tl.setRedYellowGreenState
        self.update()
        pending, self._pending = self._pending, []
        for node_id, state, link_index in pending:
            self.set_state(node_id, state, link_index)

    def update(self) -> None:
        """Mark the snapshot stale after a simulation step: every light's state, phase,
        program and next switch time are read when first asked (once per step)."""
        self._stale = self.api is not None
        if self._pinned:  # pins of a step nobody read: that step is over
            self._pinned.clear()

    def _read(self) -> None:
        """Read every light's state, phase, program and next switch time, and the time."""
        self._stale = False
        self._time = float(self._get_time())
        ids = self._ids
        if not ids:
            return
        self._states[:] = map(self._get_state, ids)
        self._programs[:] = map(self._get_program, ids)
        self._phases[:] = list(map(self._get_phase, ids))
        self._next_switch[:] = list(map(self._get_next, ids))
        for row, (state, phase, program, next_switch) in self._pinned.items():
            self._phases[row], self._next_switch[row] = phase, next_switch
            if state:  # "": no command set it (one that failed): as just read
                self._states[row] = state
            if program:
                self._programs[row] = program
        self._pinned.clear()

    # ------------------------------------------------------------------ the snapshot
    @property
    def states(self) -> list[str]:
        """Every light's state string, in :meth:`get_ids` order (updated in place each step)."""
        if self._stale:
            self._read()
        return self._states

    @property
    def phases(self) -> np.ndarray:
        """Every light's phase index, in :meth:`get_ids` order."""
        if self._stale:
            self._read()
        return self._phases

    @property
    def programs(self) -> list[str]:
        """Every light's running program id, in :meth:`get_ids` order."""
        if self._stale:
            self._read()
        return self._programs

    @property
    def next_switch(self) -> np.ndarray:
        """Every light's time of the next phase switch, s, in :meth:`get_ids` order."""
        if self._stale:
            self._read()
        return self._next_switch

    @property
    def time(self) -> float:
        """Simulation time of the snapshot, s."""
        if self._stale:
            self._read()
        return self._time

    def _row(self, node_id: str) -> int:
        row = self._index.get(node_id)
        if row is None:
            if self.api is None and node_id in self._expected:
                raise KeyError(
                    f"traffic light {node_id!r}: the simulation has not started; reset() "
                    "starts it"
                )
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
    def _pin(self, row: int, need_state: bool) -> list[Any]:
        """A command on light ``row`` while the snapshot is stale: that light's snapshot
        as SUMO showed it after the step (``[state, phase, program, next switch]``), read
        now, before the command; the command's changes go into it and it overrides the
        light's row when the whole snapshot is read. Every command sets the program, and
        the state unless ``need_state``: those are not read."""
        pin = self._pinned.get(row)
        if pin is None:
            t = self._ids[row]
            state = self._get_state(t) if need_state else ""
            pin = [state, self._get_phase(t), "", self._get_next(t)]  # "": as read later
            self._pinned[row] = pin
        elif need_state and not pin[0]:
            pin[0] = self._get_state(self._ids[row])
        return pin

    def set_state(self, node_id: str, state: str, link_index: int | str = "all") -> None:
        """Set the light's state (``link_index="all"``) or one link's signal character.

        A state longer than the light's links is cut to them (one warning per light and
        state); before the simulation starts, the command is kept and sent when it starts.

        Raises:
            KeyError: unknown light.
            ValueError: a state shorter than the light's links or with unknown characters.
        """
        if self.api is None and node_id in self._expected:
            self._pending.append((node_id, state, link_index))
            return
        row = self._row(node_id)
        n = len(self._links[row])
        if state not in self._valid_states:
            bad = sorted(set(state) - _STATE_CHARS)
            if bad:
                raise ValueError(
                    f"unknown signal character(s) {bad} in {state!r} for {node_id!r}"
                )
            self._valid_states.add(state)
        whole = link_index == "all"
        if whole:
            if len(state) != n:
                state = self._cut_to_links(node_id, state, n)
        else:
            index = int(link_index)
            if len(state) != 1 or not 0 <= index < n:
                raise ValueError(
                    f"set_state with link_index={link_index!r} needs one character and an "
                    f"index in [0, {n}), got {state!r}"
                )
        pin = self._pin(row, need_state=not whole) if self._stale else None
        if whole:
            self._set_state(node_id, state)
            new = state
        else:
            self.api.trafficlight.setLinkState(node_id, index, state)
            current = self._states[row] if pin is None else pin[0]
            new = current[:index] + state + current[index + 1 :]
        if pin is None:
            self._states[row] = new
            self._programs[row] = "online"
        else:
            pin[0], pin[2] = new, "online"

    def _cut_to_links(self, node_id: str, state: str, n: int) -> str:
        """``state`` cut to the light's ``n`` links, warned once per light and state (SUMO
        ignores the extra characters too); a shorter state is an error."""
        if len(state) < n:
            raise ValueError(
                f"state {state!r} has {len(state)} characters; light {node_id!r} controls {n} "
                "links (one character per link)"
            )
        if (node_id, state) not in self._warned:
            self._warned.add((node_id, state))
            log.warning(
                "traffic light %r controls %d links; state %r is longer and its last "
                "characters %r are ignored", node_id, n, state, state[n:],
            )  # fmt: skip
        return state[:n]

    def set_program(self, node_id: str, program_id: str) -> None:
        """Switch the light to one of its loaded programs."""
        row = self._row(node_id)
        pin = self._pin(row, need_state=True) if self._stale else None
        self.api.trafficlight.setProgram(node_id, program_id)
        if pin is None:
            self._programs[row] = program_id
        else:
            pin[2] = program_id
