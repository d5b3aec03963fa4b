"""Flow's ``k.network``: lengths, edges and positions of the current network (pure lookups)."""

from __future__ import annotations

import bisect
import copy
from typing import Any

import numpy as np

from flowrun.config.params import InitialConfig, VehicleParams
from flowrun.flow_values import FLOW_ERROR
from flowrun.kernel.lanes import LaneTable
from flowrun.networks.base import Network, NetworkSpec


class NetworkKernel:
    """Read-only facts about the network of the current episode.

    Args:
        spec: the network description.
        lanes: the lanes SUMO built (open networks): adds junction-internal edges to the
            edge starts and lengths.
    """

    def __init__(
        self, spec: NetworkSpec, lanes: LaneTable | None = None, network: Network | None = None
    ) -> None:
        self.spec = spec
        self.lanes = lanes
        self.network = network
        self._edges = {e.id: e for e in spec.edges}
        self._edge_starts = dict(spec.edge_starts if lanes is None else lanes.edge_starts)
        # every edge, junction links included (Flow's get_edge finds positions on them too)
        self._starts = sorted((s, e) for e, s in self._edge_starts.items())
        self._flow_names = flow_internal_names(network, self._edge_starts)
        self._max_speed = max((e.speed for e in spec.edges), default=0.0)
        self._length = spec.length + self._internal_length()

    def generate_starting_positions(
        self, initial_config: InitialConfig | None = None, num_vehicles: int | None = None,
        net_params: Any = None,
    ) -> tuple[list[tuple[str, float]], list[int]]:  # fmt: skip
        """Flow's starting positions: ``([(edge, position), ...], [lane, ...])``.

        With the network's placement rules and ``initial_config`` (default: the network's
        own), for ``num_vehicles`` cars of the network's first vehicle type (default: the
        network's vehicles); draws from a generator seeded with 0.

        Raises:
            RuntimeError: no network object is known (a kernel built from a bare spec).
        """
        if self.network is None:
            raise RuntimeError("starting positions need the network object; reset the env first")
        net = copy.copy(self.network)
        if initial_config is not None:
            net.initial_config = initial_config
        if num_vehicles is not None:
            vehicles = VehicleParams()
            first = self.network.vehicles.groups[0] if self.network.vehicles.groups else None
            vehicles.add(
                "veh",
                num_vehicles=num_vehicles,
                car_following_params=first.car_following_params if first else None,
            )
            net.vehicles = vehicles
        start = net.start_positions(np.random.default_rng(0))
        return list(zip(start.edges, start.lane_pos, strict=True)), list(start.lanes)

    def length(self) -> float:
        """Total length of the network, m: its edges plus, once SUMO has built them, its
        junction-internal edges (Flow's ``length``; see :meth:`non_internal_length`)."""
        return self._length

    def _internal_length(self) -> float:
        if self.lanes is None:
            return 0.0
        facts = self.lanes.edge_facts
        return float(sum(f[1] for e, f in facts.items() if e.startswith(":")))

    def edge_length(self, edge_id: str) -> float:
        """Length of one edge, m (internal edges included; -1001 for an unknown edge)."""
        if edge_id in self._edges:
            return self._edges[edge_id].length
        facts = self._facts(edge_id)
        return FLOW_ERROR if facts is None else facts[1]

    def _facts(self, edge_id: str) -> tuple[int, float, float] | None:
        """(lanes, length, speed limit) of an edge SUMO built (junction-internal ones too)."""
        return None if self.lanes is None else self.lanes.edge_facts.get(edge_id)

    def non_internal_length(self) -> float:
        """Total length of the non-internal edges, m."""
        return float(sum(e.length for e in self.spec.edges))

    def get_edge_list(self) -> list[str]:
        """All edge ids."""
        return list(self._edges)

    def num_lanes(self, edge_id: str) -> int:
        """Number of lanes of an edge (-1001 for an unknown edge, as Flow)."""
        if edge_id in self._edges:
            return self._edges[edge_id].lanes
        facts = self._facts(edge_id)
        return int(FLOW_ERROR) if facts is None else facts[0]

    def speed_limit(self, edge_id: str) -> float:
        """Speed limit of an edge, m/s (-1001 for an unknown edge, as Flow)."""
        if edge_id in self._edges:
            return self._edges[edge_id].speed
        facts = self._facts(edge_id)
        return FLOW_ERROR if facts is None else facts[2]

    def next_edge(self, edge: str, lane: int) -> list[tuple[str, int]]:
        """The (edge, lane) pairs lane ``lane`` of ``edge`` leads to (empty if none/unknown).

        Known once the simulation has started (the junctions are SUMO's).
        """
        if self.lanes is not None:
            return self.lanes.next_lanes(edge, lane)
        if self.spec.closed and edge in self._edges:
            ids = [e.id for e in self.spec.edges]
            nxt = self.spec.edges[(ids.index(edge) + 1) % len(ids)]
            return [(nxt.id, lane)] if lane < nxt.lanes else []
        return []

    def prev_edge(self, edge: str, lane: int) -> list[tuple[str, int]]:
        """The (edge, lane) pairs that lead into lane ``lane`` of ``edge``."""
        if self.lanes is not None:
            return self.lanes.prev_lanes(edge, lane)
        if self.spec.closed and edge in self._edges:
            ids = [e.id for e in self.spec.edges]
            prev = self.spec.edges[(ids.index(edge) - 1) % len(ids)]
            return [(prev.id, lane)] if lane < prev.lanes else []
        return []

    def max_speed(self) -> float:
        """Highest speed limit in the network, m/s."""
        return self._max_speed

    def get_junction_list(self) -> list[str]:
        """Ids of the junction-internal edges (``":center_0"``, ...), Flow's
        ``get_junction_list``: SUMO's once it has built the network, else the ones the network
        lists in its edge starts. Empty for the ring (no internal links)."""
        lanes = self.lanes
        names = list(lanes.edge_pos) if lanes is not None else list(self._edge_starts)
        return [e for e in names if e.startswith(":")]

    def get_x(self, edge: str, position: float) -> float:
        """Position along the network of ``position`` metres into ``edge`` (-1001 for an
        unknown edge, as Flow).

        Flow's figure eight lists its internal edges by junction (``":bottom"``) where SUMO
        names them ``":bottom_0"``; a junction name without the index is read as its first
        internal edge, so Flow code using either name gets the same position.
        """
        start = self._edge_starts.get(edge)
        if start is None and edge.startswith(":"):
            start = self._edge_starts.get(f"{edge}_0")
        if start is None:
            return FLOW_ERROR
        return start + position

    def get_edge(self, x: float) -> tuple[str, float]:
        """Edge and position on it of network position ``x`` (wrapped on closed networks),
        as Flow: the last edge starting at or before ``x``, junction links included. A
        junction link the network names Flow's way (``":bottom"`` for SUMO's
        ``":bottom_0"``, see :func:`flow_internal_names`) is given by that name."""
        if self.spec.closed:
            x = x % self.length()
        keys = [s for s, _ in self._starts]
        i = max(bisect.bisect_right(keys, x) - 1, 0)
        start, edge = self._starts[i]
        return self._flow_names.get(edge, edge), x - start

    @property
    def rts(self) -> dict[str, list[tuple[list[str], float]]]:
        """Routes by starting edge, each a list of ``(edges, probability)`` (Flow's ``rts``,
        which Flow's routers read as ``env.available_routes``)."""
        edges = dict.fromkeys((*self.spec.routes, *self.spec.route_choices))
        return {e: [(list(r), float(p)) for r, p in self.spec.choices(e)] for e in edges}

    @property
    def total_edgestarts_dict(self) -> dict[str, float]:
        """Start position of every edge (Flow's name)."""
        return dict(self._edge_starts)


def flow_internal_names(network: Any, edge_starts: dict[str, float]) -> dict[str, str]:
    """SUMO id -> Flow's name of the junction links a network names without the lane index.

    Flow's networks list some junction links by junction (``specify_internal_edge_starts``
    gives ``":bottom"`` where SUMO's edge is ``":bottom_0"``); ``FLOW_INTERNAL_NAMES`` of a
    flowrun network says the same. Names that are SUMO ids already map to nothing.
    """
    names: dict[str, str] = dict(getattr(network, "FLOW_INTERNAL_NAMES", None) or {})
    hook = getattr(network, "specify_internal_edge_starts", None)
    try:
        declared = list(hook() or ()) if callable(hook) else []
    except Exception:  # a user's hook that needs more than the network: no aliases
        declared = []
    for name, _ in declared:
        name = str(name)
        if name not in edge_starts and f"{name}_0" in edge_starts:
            names[f"{name}_0"] = name
    return {sumo: flow for sumo, flow in names.items() if sumo in edge_starts}
