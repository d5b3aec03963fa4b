"""Flow's ``flow.core.kernel.kernel.Kernel(simulator, sim_params)`` and the lifecycle Flow code
drives by hand::

    k = Kernel("traci", sim_params)
    k.network.generate_network(network)      # the SUMO files of the network
    k.simulation.start_simulation(network=k.network, sim_params=sim_params)
    ...                                      # k.kernel_api is libsumo
    k.simulation.teardown_sumo()             # (or k.close())

A thin layer over :class:`flowrun.kernel.Kernel`: the same files and the same SUMO command.
SUMO runs in this process through libsumo, so ``k.simulation.sumo_proc`` is the running
:class:`~flowrun.kernel.sumo.SumoProcess` (there is no operating-system process: tearing down
closes the in-process simulation), and ``start_simulation`` returns the ``libsumo`` module,
Flow's kernel API. As Flow's, starting runs one step on the empty network. The vehicles, their
controllers and the per-step snapshot (``env.k.vehicle``) come with flowrun's ``Env``, which
builds and drives its own kernel; this class is for the lifecycle alone.
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
from pathlib import Path
from typing import Any

from flowrun.config.params import SumoParams
from flowrun.errors import ConfigError, SimulationError
from flowrun.kernel import Kernel as FlowrunKernel
from flowrun.kernel.network import NetworkKernel
from flowrun.kernel.sumo import SumoProcess
from flowrun.networks.base import Network


class NetworkLifecycle:
    """Flow's ``k.network``: ``generate_network(network)``, then the network's getters
    (``length()``, ``edge_length(edge)``, ...) of :class:`~flowrun.kernel.network.NetworkKernel`."""

    def __init__(self, owner: Kernel) -> None:
        self._owner = owner
        self.network: Network | None = None
        self._getters: NetworkKernel | None = None

    def generate_network(self, network: Network) -> None:
        """Write ``network``'s SUMO files (Flow's ``generate_network``)."""
        self._owner.files = self._owner.kernel.write_files(network)
        self.network = network
        self._getters = NetworkKernel(network.spec, network=network)

    def __getattr__(self, name: str) -> Any:
        getters = self.__dict__.get("_getters")
        if getters is None:
            raise AttributeError(
                f"k.network.{name}: no network yet; call k.network.generate_network(network) first"
            )
        return getattr(getters, name)


class SimulationLifecycle:
    """Flow's ``k.simulation``: ``start_simulation``, ``sumo_proc``, ``teardown_sumo``."""

    def __init__(self, owner: Kernel) -> None:
        self._owner = owner
        #: the running in-process simulation (Flow: the ``sumo`` subprocess); ``None`` when
        #: none runs
        self.sumo_proc: SumoProcess | None = None

    def start_simulation(self, network: Any = None, sim_params: SumoParams | None = None) -> Any:
        """Start SUMO on the generated network and step it once; return the kernel API.

        Raises:
            ConfigError: ``k.network.generate_network`` was not called first.
            SimulationError: SUMO failed to start.
        """
        owner = self._owner
        if owner.files is None:
            raise ConfigError(
                "start_simulation before generate_network: call "
                "k.network.generate_network(network) first"
            )
        self.teardown_sumo()
        self.sumo_proc = SumoProcess(owner.files, sim_params or owner.sim_params)
        api = self.sumo_proc.start()
        api.simulationStep()  # Flow's: one step on the empty network
        owner.kernel_api = api
        return api

    def simulation_step(self) -> None:
        """Advance SUMO one step."""
        self._api().simulationStep()

    def teardown_sumo(self) -> None:
        """Stop the simulation (safe to call twice)."""
        if self.sumo_proc is not None:
            self.sumo_proc.close()
            self.sumo_proc = None
            self._owner.kernel_api = None

    def _api(self) -> Any:
        api = self._owner.kernel_api
        if api is None:
            raise SimulationError("no simulation runs: call k.simulation.start_simulation first")
        return api


class Kernel:
    """Flow's kernel object for its manual lifecycle (see the module docstring).

    Args:
        simulator: ``"traci"`` (Flow's name for SUMO; the only simulator flowrun drives).
        sim_params: simulation settings.

    Raises:
        ConfigError: another simulator (Flow's ``"aimsun"``).
    """

    def __init__(self, simulator: str, sim_params: SumoParams) -> None:
        if simulator != "traci":
            raise ConfigError(
                f"simulator {simulator!r} is not supported: flowrun drives SUMO only; use 'traci'"
            )
        self.simulator = simulator
        self.sim_params = sim_params
        self.work_dir = Path(tempfile.mkdtemp(prefix="flowrun-kernel-"))
        self.kernel = FlowrunKernel(sim_params, self.work_dir)
        self.files: Any = None
        self.kernel_api: Any = None
        self.network = NetworkLifecycle(self)
        self.simulation = SimulationLifecycle(self)

    def close(self) -> None:
        """Stop the simulation and remove the generated files (safe to call twice)."""
        self.simulation.teardown_sumo()
        shutil.rmtree(self.work_dir, ignore_errors=True)

    def __del__(self) -> None:
        with contextlib.suppress(Exception):  # interpreter shutdown
            self.close()
