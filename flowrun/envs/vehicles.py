"""From ``VehicleParams`` to the kernel's vehicle table and the per-group controller objects."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flowrun.config.params import LANE_CHANGE_MODES, SPEED_MODES, VehicleParams
from flowrun.controllers.base import AccelerationController
from flowrun.controllers.registry import build_controller, resolve_controller
from flowrun.errors import ConfigError
from flowrun.kernel.snapshot import VehicleTable
from flowrun.networks.base import StartPositions
from flowrun.suggest import unknown_name


@dataclass
class GroupControl:
    """The acceleration controller of one vehicle group and the vehicle indices it drives."""

    name: str
    index: np.ndarray
    controller: AccelerationController
    #: the same vehicles as a slice (groups are contiguous in placement order): a view, no copy
    sl: slice = field(init=False)

    def __post_init__(self) -> None:
        start = int(self.index[0]) if self.index.size else 0
        self.sl = slice(start, start + int(self.index.size))


def mode_value(mode: str | int, table: dict[str, int], what: str) -> int:
    """A Flow mode name (or a raw SUMO int) as SUMO's integer bit set."""
    if isinstance(mode, int) and not isinstance(mode, bool):
        return mode
    if mode not in table:
        raise ConfigError(unknown_name(what, str(mode), table))
    return table[mode]


def build_controllers(vehicles: VehicleParams) -> list[GroupControl]:
    """One acceleration controller per group, with the indices of its vehicles."""
    controls = []
    start = 0
    for g in vehicles.groups:
        idx = np.arange(start, start + g.num_vehicles)
        start += g.num_vehicles
        spec = g.acceleration_controller
        ctrl: Any = build_controller(spec.type, dict(spec.params))
        controls.append(GroupControl(g.veh_id, idx, ctrl))
    return controls


def _routed_continuously(route_type: str | None) -> bool:
    if route_type is None:
        return False
    cls = resolve_controller(route_type)
    return bool(getattr(cls, "registered_name", cls.__name__) == "ContinuousRouter")


def build_table(
    vehicles: VehicleParams, controls: list[GroupControl], start: StartPositions
) -> VehicleTable:
    """The kernel's static vehicle table for one episode."""
    ids, types, group, is_rl, commanded, continuous = [], [], [], [], [], []
    lengths, max_speeds, initial, speed_modes, lc_modes = [], [], [], [], []
    for gi, (g, ctl) in enumerate(zip(vehicles.groups, controls, strict=True)):
        c = ctl.controller
        routed = _routed_continuously(g.routing_controller.type if g.routing_controller else None)
        speed_mode = mode_value(g.car_following_params.speed_mode, SPEED_MODES, "speed_mode")
        lc_mode = mode_value(
            g.lane_change_params.lane_change_mode, LANE_CHANGE_MODES, "lane_change_mode"
        )
        for i in range(g.num_vehicles):
            ids.append(f"{g.veh_id}_{i}")
            types.append(g.veh_id)
            group.append(gi)
            is_rl.append(bool(c.is_rl))
            commanded.append(bool(c.commands_sumo and not c.is_rl))
            continuous.append(routed)
            lengths.append(g.car_following_params.length)
            max_speeds.append(g.car_following_params.max_speed)
            initial.append(float(g.initial_speed))
            speed_modes.append(speed_mode)
            lc_modes.append(lc_mode)
    return VehicleTable(
        ids=ids,
        types=types,
        group=np.array(group, dtype=np.int64),
        is_rl=np.array(is_rl, dtype=bool),
        commanded=np.array(commanded, dtype=bool),
        continuous=np.array(continuous, dtype=bool),
        lengths=np.array(lengths, dtype=np.float64),
        max_speeds=np.array(max_speeds, dtype=np.float64),
        start_edges=start.edges,
        start_lane_pos=start.lane_pos,
        start_lanes=start.lanes,
        initial_speeds=initial,
        speed_modes=speed_modes,
        lane_change_modes=lc_modes,
    )
