"""The kernel facade (Flow's ``env.k``): one SUMO simulation and its per-step snapshot."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from flowrun.config.params import SumoParams
from flowrun.errors import SimulationError
from flowrun.kernel.lane_neighbours import lane_graph
from flowrun.kernel.lanes import LaneTable
from flowrun.kernel.network import NetworkKernel
from flowrun.kernel.population import VehicleTable
from flowrun.kernel.ring_reader import ring_fast_path
from flowrun.kernel.simulation import SimulationKernel
from flowrun.kernel.sumo import SumoFiles, SumoProcess
from flowrun.kernel.traffic_light import TrafficLightKernel
from flowrun.kernel.vehicle import VehicleKernel
from flowrun.networks.base import Network, TemplateVehicle
from flowrun.networks.build import build_network
from flowrun.networks.routes import route_name, routes_xml
from flowrun.networks.template_demand import sumo_route_files
from flowrun.networks.tls import write_tls_file

log = logging.getLogger(__name__)


class Kernel:
    """Starts, resets, steps and closes SUMO; serves ``vehicle``, ``network``, ``simulation``.

    Args:
        sim_params: simulation settings.
        work_dir: folder for the generated SUMO files (network, routes).
        gui: run ``sumo-gui`` over TraCI instead of libsumo.
    """

    def __init__(self, sim_params: SumoParams, work_dir: Path, gui: bool = False) -> None:
        self.sim_params = sim_params
        self.work_dir = work_dir
        self.gui = gui
        self.process: SumoProcess | None = None
        self.vehicle: VehicleKernel
        self.network: NetworkKernel
        self.simulation = SimulationKernel(sim_params.sim_step)
        self.traffic_light = TrafficLightKernel()
        self.net_file: Path | None = None
        #: a template's route files as given to SUMO, by what decides them (read and
        #: filtered once, not at every reset: an I-210 route file is megabytes)
        self._route_files: dict[tuple[object, ...], tuple[Path, ...]] = {}
        #: routers of whole vehicle groups (``GroupRouters``), run at every vehicle update
        self.group_routers: Any = None

    @property
    def scenario(self) -> NetworkKernel:
        """Flow < 0.5 name of :attr:`network`."""
        return self.network

    @property
    def started(self) -> bool:
        """Whether a simulation is running."""
        return self.process is not None and self.process.api is not None

    def reset(
        self,
        network: Network,
        table: VehicleTable,
        read_xy: bool = True,
        rng: np.random.Generator | None = None,
    ) -> None:
        """(Re)start SUMO on ``network`` with the vehicles of ``table`` at their start positions.

        Restarting libsumo costs a few milliseconds and reproduces a fresh start exactly.
        As in Flow, one step runs on the empty network before the cars are inserted, and the
        insertion takes another: the clock reads ``2 * sim_step`` afterwards.

        Raises:
            SimulationError: SUMO failed, or not every vehicle could be inserted.
        """
        self.close()
        spec = network.spec
        self.process = SumoProcess(self.write_files(network), self.sim_params, self.gui)
        api = self.process.start()
        try:
            # Flow's start_simulation steps SUMO once on the empty network before its reset
            # inserts the cars (and restart_instance repeats both), so after reset the clock
            # reads 2 steps, as Flow's: signal programs and inflows keep Flow's phase.
            api.simulationStep()
            self._insert(api, table)
            self._schedule(api, spec.departures)
        except Exception:
            self.close()
            raise
        ring = ring_fast_path(spec, table)
        lanes = None if ring else LaneTable.read(api, spec)
        self.network = NetworkKernel(spec, lanes, network)
        self.vehicle = VehicleKernel(table, spec, self.sim_params.sim_step, rng)
        self.vehicle.read_xy = read_xy
        self.vehicle.group_routers = self.group_routers
        self.vehicle.lane_view = lane_graph(self.network)  # Flow's lane leaders' search
        self.vehicle.attach(api, lanes)
        self.simulation.attach(api)
        self.traffic_light.attach(api)
        self.simulation.before_step = self.vehicle.send_commands
        self.simulation.after_teleport = self.vehicle.resync
        self.vehicle.update(first=True)

    def write_files(self, network: Network) -> SumoFiles:
        """Write ``network``'s SUMO files into the work folder: the network (built by
        netconvert, or the template), its vehicle types, routes and inflows, and its signal
        programs."""
        spec = network.spec
        self.net_file = build_network(spec, self.work_dir, name=network.network_type or "network")
        self.work_dir.mkdir(parents=True, exist_ok=True)  # a template is not built there
        routes = self.work_dir / f"{self.net_file.stem.removesuffix('.net')}.rou.xml"
        routes.write_text(routes_xml(spec, network.vehicles, network.net_params.inflows))
        extra = self._template_route_files(network)
        tls_file = write_tls_file(network.traffic_lights, self.net_file, self.work_dir)
        tls = () if tls_file is None else (tls_file,)
        return SumoFiles(self.net_file, routes, extra, tls)

    def _template_route_files(self, network: Network) -> tuple[Path, ...]:
        """A template's route files less what flowrun defines (its vehicle types and the
        vehicles it adds at reset), written once per combination."""
        spec = network.spec
        types = frozenset(network.vehicles.type_names)
        added = frozenset(d.id for d in spec.departures)
        key = (tuple(spec.extra_files), types, added)
        files = self._route_files.get(key)
        if files is None or not all(f.is_file() for f in files):
            files = sumo_route_files(spec.extra_files, set(types), set(added), self.work_dir)
            self._route_files[key] = files
        return files

    def _insert(self, api: Any, table: VehicleTable) -> None:
        v = api.vehicle
        for i, vid in enumerate(table.ids):
            v.add(
                vid,
                routeID=table.routes[i] or route_name(table.start_edges[i]),
                typeID=table.classes[int(table.group[i])].name,
                depart="now",
                departLane=str(table.start_lanes[i]),
                departPos=repr(table.start_lane_pos[i]),
                departSpeed=repr(table.initial_speeds[i]),
            )
        api.simulationStep()
        missing = sorted(set(table.ids) - set(v.getIDList())) if table.size else []
        if missing:
            raise SimulationError(
                f"SUMO could not insert {len(missing)} of {table.size} vehicles "
                f"({', '.join(missing[:5])}...): the initial gaps are too small for the vehicle "
                "types' minGap; use fewer vehicles, a longer network or less bunching"
            )
        for i, vid in enumerate(table.ids):
            c = table.classes[int(table.group[i])]
            v.setSpeedMode(vid, c.speed_mode)
            v.setLaneChangeMode(vid, c.lane_change_mode)

    def _schedule(self, api: Any, departures: tuple[TemplateVehicle, ...]) -> None:
        """Add a template's vehicles as Flow does at each reset: on route ``route<id>_0``,
        departing at their time plus the reset's two steps (the clock now), lane ``first``."""
        offset = 2 * self.sim_params.sim_step
        for d in departures:
            try:
                api.route.add(f"route{d.id}_0", list(d.route))
                api.vehicle.add(
                    d.id, f"route{d.id}_0", typeID=d.type, depart=repr(d.depart + offset),
                    departLane="first", departPos=d.depart_pos, departSpeed=d.depart_speed,
                )  # fmt: skip
            except Exception as err:  # libsumo's TraCIException: bad departPos, ...
                raise SimulationError(
                    f"SUMO refused the template vehicle '{d.id}' ({err}); check its "
                    "departPos/departSpeed and route in the rou file"
                ) from None

    def step(self) -> None:
        """Send buffered commands, advance one step, read the new state."""
        self.simulation.simulation_step()
        self.vehicle.update()
        self.traffic_light.update()

    def update(self, reset: bool = False) -> None:
        """Read the new state after a ``simulation_step`` (Flow's ``k.update(reset)``)."""
        self.vehicle.update(reset)
        self.traffic_light.update()

    def close(self) -> None:
        """Stop SUMO (safe to call twice)."""
        if self.process is not None:
            self.process.close()
            self.process = None
