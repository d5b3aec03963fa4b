"""Flow's ``k.simulation``: time, stepping, and collision/teleport accounting."""

from __future__ import annotations

from typing import Any


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

    def attach(self, api: Any) -> None:
        """Bind to a freshly started simulation and zero the counters."""
        self.api = api
        self.collisions = self.teleports = 0
        self.step_collisions = self.step_teleports = 0
        self.step_count = 0
        self.colliding_ids = []
        self.time = float(api.simulation.getTime())

    def simulation_step(self) -> None:
        """Advance SUMO by one step and count what it reported."""
        sim = self.api.simulation
        sim.step()
        self.step_count += 1
        self.time = float(sim.getTime())
        self.step_collisions = int(sim.getCollidingVehiclesNumber())
        self.step_teleports = int(sim.getStartingTeleportNumber())
        if self.step_collisions:
            self.colliding_ids = list(sim.getCollidingVehiclesIDList())
        self.collisions += self.step_collisions
        self.teleports += self.step_teleports

    def check_collision(self) -> bool:
        """Whether SUMO reported a collision (or a teleport) in the last step."""
        return bool(self.step_collisions or self.step_teleports)
