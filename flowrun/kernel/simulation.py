"""Flow's ``k.simulation``: time, stepping, and collision/teleport accounting."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from flowrun.kernel.sumo import FastCalls


class SimulationKernel:
    """Simulation clock and per-step safety counters of the current episode."""

    def __init__(self, sim_step: float) -> None:
        self.sim_step = sim_step
        self.api: Any = None
        self.time = 0.0
        self.step_count = 0
        self.collisions = 0
        self.teleports = 0
        self.step_collisions = 0
        self.step_teleports = 0
        self.colliding_ids: list[str] = []
        #: called right before each step: the vehicle kernel's buffered commands go out, so
        #: Flow's ``apply_acceleration(...); simulation_step(); update(False)`` works as in Flow
        self.before_step: Callable[[], None] | None = None
        #: called after a step in which SUMO teleported cars (the vehicle kernel re-checks
        #: who is on the road: SUMO's departed/arrived lists do not report teleports)
        self.after_teleport: Callable[[], None] | None = None

    def attach(self, api: Any) -> None:
        """Bind to a freshly started simulation and zero the counters."""
        self.api = api
        self._fast = FastCalls.of(api)
        self.collisions = self.teleports = 0
        self.step_collisions = self.step_teleports = 0
        self.step_count = 0
        self.colliding_ids = []
        self.time = float(api.simulation.getTime())

    def simulation_step(self) -> None:
        """Send pending vehicle commands, advance SUMO by one step, count what it reported."""
        if self.before_step is not None:
            self.before_step()
        fast = self._fast
        fast.sim_step(0.0)
        self.step_count += 1
        self.time = fast.sim_time()
        self.step_collisions = collisions = fast.colliding_number()
        self.step_teleports = teleports = fast.teleport_number()
        if collisions:
            self.colliding_ids = list(self.api.simulation.getCollidingVehiclesIDList())
        self.collisions += collisions
        self.teleports += teleports
        if teleports and self.after_teleport is not None:
            self.after_teleport()

    def check_collision(self) -> bool:
        """Whether SUMO reported a collision (or a teleport) in the last step."""
        return bool(self.step_collisions or self.step_teleports)
