"""Starting and stopping SUMO: the one place that imports ``libsumo`` (and ``traci`` for a GUI).

libsumo runs one simulation per process and a second ``start`` silently replaces the first,
so a process-wide guard closes the running :class:`SumoProcess` (with a warning) before another
starts; the displaced owner sees ``api is None`` and must start again (an env: ``reset()``).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from flowrun.config.params import SumoParams
from flowrun.errors import SimulationError
from flowrun.networks.build import sumo_binary

log = logging.getLogger(__name__)

_ACTIVE: list[SumoProcess] = []  # at most one running libsumo simulation per process


@dataclass(frozen=True)
class SumoFiles:
    """Files one simulation reads: the network and the vehicle types/routes."""

    net: Path
    routes: Path
    extra_routes: tuple[Path, ...] = ()
    additional: tuple[Path, ...] = ()  # e.g. signal programs (networks/tls.py)


def sumo_command(files: SumoFiles, params: SumoParams, gui: bool) -> list[str]:
    """The full SUMO command line (argv[0] included), built in one place.

    Collisions are reported, never silent (``warn``, counted every step) and only real
    overlaps count (``--collision.mingap-factor 0``: normal IDM close-following below the
    vehicle type's ``minGap`` is not a crash). Teleporting is off unless asked for.
    """
    cmd = [
        sumo_binary("sumo-gui" if gui else "sumo"),
        "--net-file",
        str(files.net),
        "--route-files",
        # flowrun's own file first: a template's <flow> may use a vType defined there
        ",".join(str(f) for f in (files.routes, *files.extra_routes)),
        "--step-length",
        repr(float(params.sim_step)),
        "--seed",
        str(int(params.seed or 0)),
        "--time-to-teleport",
        repr(float(params.teleport_time)),
        "--collision.action",
        "warn",
        "--collision.mingap-factor",
        "0",
        "--collision.check-junctions",
        "true",
        "--no-step-log",
        "true",
        "--duration-log.disable",
        "true",
        "--begin",
        "0",
    ]
    if files.additional:
        cmd += ["--additional-files", ",".join(str(f) for f in files.additional)]
    if not params.print_warnings:
        cmd += ["--no-warnings", "true"]
    if getattr(params, "overtake_right", False):
        cmd += ["--lanechange.overtake-right", "true"]
    if params.use_ballistic:
        cmd += ["--step-method.ballistic", "true"]
    if params.lateral_resolution is not None:
        cmd += ["--lateral-resolution", repr(float(params.lateral_resolution))]
    if gui:
        cmd += ["--start", "true", "--quit-on-end", "true"]
    return cmd


def gui_available() -> bool:
    """Whether ``sumo-gui`` can open a window here (a display and the binary)."""
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return False
    try:
        sumo_binary("sumo-gui")
    except SimulationError:
        return False
    return True


@dataclass(frozen=True)
class FastCalls:
    """The calls made every step, bound once.

    libsumo's Python wrappers add a function layer over the compiled calls; on the hot path
    the compiled ones are used directly (same arguments, same results). TraCI keeps its own.
    """

    get_speed: Callable[[str], float]
    get_distance: Callable[[str], float]
    get_position: Callable[[str], tuple[float, float]]
    slow_down: Callable[[str, float, float], None]
    sim_step: Callable[[float], object]
    sim_time: Callable[[], float]
    colliding_number: Callable[[], int]
    teleport_number: Callable[[], int]
    get_lane_id: Callable[[str], str]
    get_lane_position: Callable[[str], float]
    departed_ids: Callable[[], Sequence[str]]
    arrived_ids: Callable[[], Sequence[str]]

    @staticmethod
    def of(api: Any) -> FastCalls:
        """The fastest equivalent calls of ``api`` (``libsumo`` or ``traci``)."""
        raw = getattr(api, "_libsumo", None)
        if raw is not None and hasattr(raw, "vehicle_getSpeed"):
            return FastCalls(
                raw.vehicle_getSpeed,
                raw.vehicle_getDistance,
                raw.vehicle_getPosition,
                raw.vehicle_slowDown,
                raw.simulation_step,
                raw.simulation_getTime,
                raw.simulation_getCollidingVehiclesNumber,
                raw.simulation_getStartingTeleportNumber,
                raw.vehicle_getLaneID,
                raw.vehicle_getLanePosition,
                raw.simulation_getDepartedIDList,
                raw.simulation_getArrivedIDList,
            )
        v, sim = api.vehicle, api.simulation
        return FastCalls(
            v.getSpeed,
            v.getDistance,
            v.getPosition,
            v.slowDown,
            sim.step,
            sim.getTime,
            sim.getCollidingVehiclesNumber,
            sim.getStartingTeleportNumber,
            v.getLaneID,
            v.getLanePosition,
            sim.getDepartedIDList,
            sim.getArrivedIDList,
        )


class SumoProcess:
    """One running SUMO simulation (libsumo in-process, or sumo-gui over TraCI).

    Use as a context manager; :meth:`close` is idempotent.
    """

    def __init__(self, files: SumoFiles, params: SumoParams, gui: bool = False) -> None:
        self.files = files
        self.params = params
        self.gui = gui
        self.api: Any = None

    def start(self) -> ModuleType:
        """Start the simulation and return the API module (``libsumo`` or ``traci``)."""
        if self.api is not None:
            return self.api
        for other in list(_ACTIVE):
            log.warning(
                "a SUMO simulation is already running in this process; stopping it to start "
                "another (libsumo allows one per process: use one subprocess per environment "
                "to run several at once)"
            )
            other.close()
        module: ModuleType
        if self.gui:
            import traci

            module = traci
        else:
            import libsumo

            module = libsumo
        cmd = sumo_command(self.files, self.params, self.gui)
        try:
            module.start(cmd)
        except Exception as err:  # libsumo raises its own TraCIException / FatalTraCIError
            raise SimulationError(f"SUMO failed to start ({' '.join(cmd)}): {err}") from err
        self.api = module
        _ACTIVE.append(self)
        return module

    def close(self) -> None:
        """Stop the simulation (safe to call twice)."""
        if self.api is None:
            return
        try:
            self.api.close()
        except Exception as err:  # closing a dead connection is not an error for us
            log.debug("closing SUMO: %s", err)
        finally:
            self.api = None
            if self in _ACTIVE:
                _ACTIVE.remove(self)

    def __enter__(self) -> SumoProcess:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def sumo_version() -> str:
    """SUMO's version string, from the eclipse-sumo wheel's metadata."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("eclipse-sumo")
    except PackageNotFoundError:  # pragma: no cover
        return "unknown"
