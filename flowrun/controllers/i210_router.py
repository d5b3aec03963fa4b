"""Flow's ``I210Router``: the continuous router of the I-210 sub-network, plus one lane rule.

Flow's rule (``flow/controllers/routing_controllers.py``): cars in lanes 3, 4 and 5 of the
edge ``119257908#1-AddedOffRampEdge`` "are not going to be able to make it out in time" to
the off-ramp, so they take that edge's first route (Flow's
``env.available_routes[edge][0][0]``); elsewhere a car on its route's last edge draws one of
the routes starting there by their probabilities, as :class:`ContinuousRouter` does. flowrun
routes all cars of a group at once from the kernel's seeded generator (never ``random``) and
reroutes a car only when its route must change.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from flowrun.controllers.routing import ContinuousRouter, pick_route


class I210Router(ContinuousRouter):
    """Flow's ``I210Router`` (see the module docstring); a group router (``route_vehicles``)."""

    registered_name = "I210Router"
    #: the edge whose far-left lanes cannot reach the off-ramp, and those lanes
    KEEP_EDGE: ClassVar[str] = "119257908#1-AddedOffRampEdge"
    KEEP_LANES: ClassVar[frozenset[int]] = frozenset({3, 4, 5})

    def reroute_mask(self, edges_left: Any) -> npt.NDArray[np.bool_]:
        """None: :meth:`route_vehicles` routes this group."""
        return np.zeros(np.asarray(edges_left).shape, dtype=bool)

    def route_vehicles(
        self, vk: Any, lanes: Any, rows: np.ndarray, rng: np.random.Generator
    ) -> tuple[list[int], list[list[str]]]:
        """New routes for the group's cars that need one (called by the kernel each update).

        Args:
            vk: the vehicle kernel, this step's state read (edges, lanes, route ends).
            lanes: the network's lanes (``None`` on a closed ring: nothing to do).
            rows: the group's rows in the vehicle arrays.
            rng: the generator of the random choices.

        Returns:
            The rows of the cars to reroute and their new routes.
        """
        if lanes is None or not rows.size:
            return [], []
        names, spec = vk.edge_names, vk.spec
        edge_index, route_end, lane = vk.edge_index[rows], vk.route_end[rows], vk.lanes[rows]
        out_rows: list[int] = []
        routes: list[list[str]] = []
        for row, at, end, ln in zip(rows.tolist(), edge_index, route_end, lane, strict=True):
            if at < 0:
                continue
            edge = names[int(at)]
            choices = spec.choices(edge)
            if not choices:
                continue
            if edge == self.KEEP_EDGE and int(ln) in self.KEEP_LANES:
                route = list(choices[0][0])
                if end >= 0 and names[int(end)] == route[-1]:
                    continue  # already on it
            elif at == end:
                route = pick_route(choices, rng)
            else:
                continue
            out_rows.append(row)
            routes.append(route)
        return out_rows, routes
